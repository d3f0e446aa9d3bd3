#!/bin/bash
# The store is readable by standard tools: h5dump, and h5py (checked by check_store.py:
# layout, units, no NaN, ragged indices, and one realization against `campaign simulate`).
source "$(dirname "$0")/lib.sh"
reference
h5dump -H "$WORK/ref.h5" >dump.txt || fail "h5dump failed"
expect_in dump.txt 'GROUP "realizations"'
h5dump -d /realizations/status "$WORK/ref.h5" >status_dump.txt || fail "h5dump -d failed"
expect_in status_dump.txt '"complete"'
"$PY" "$SRC/tests/campaign/check_store.py" "$WORK/ref.h5" "$EXE" "$MINI" || fail "check_store.py"
echo "ok"
