#!/bin/bash
# Runs one of the campaign test scripts N times beside HOGS busy loops (default 4: twice the
# cores of the 2-core CI machine), the way to look for a test that fails only under load.
# Not part of ctest. From the repository root, after a build:
#   tests/campaign/under_load.sh tests/campaign/hybrid.sh 5 [script args...]
#   HOGS=8 tests/campaign/under_load.sh tests/campaign/signals.sh 3 3
# Prints each failing run's last lines and "N passed, M failed"; exits 1 if any failed.
set -u
[ $# -ge 2 ] || { sed -n '2,8p' "$0" >&2; exit 2; }
script=$1 runs=$2
shift 2
build=${BUILD:-build}
export EXE=$PWD/$build/src/cli/campaign DIGEST=$PWD/$build/tests/campaign/store_digest SRC=$PWD
export PY=/usr/bin/python3 NOLOCKS=$PWD/$build/tests/campaign/libhopper_no_locks.so
[ -x "$EXE" ] && [ -x "$DIGEST" ] || { echo "under_load: build first ($EXE, $DIGEST)" >&2; exit 2; }
hogs=()
trap 'kill "${hogs[@]}" 2>/dev/null' EXIT
for _ in $(seq "${HOGS:-4}"); do (while :; do :; done) & hogs+=($!); done
pass=0 failed=0
for r in $(seq "$runs"); do
    log=$(mktemp)
    if WORK=$PWD/$build/tests/campaign/tmp/under_load bash "$script" "$@" >"$log" 2>&1; then
        pass=$((pass + 1))
    else
        failed=$((failed + 1))
        echo "run $r failed:" >&2
        tail -n 3 "$log" >&2
    fi
    rm -f "$log"
done
echo "$(basename "$script"): $pass passed, $failed failed (beside ${HOGS:-4} busy loops)"
[ "$failed" -eq 0 ]
