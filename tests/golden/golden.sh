#!/usr/bin/env bash
# Golden regression check (issue 28; tests/golden/README.md): runs every campaign file here
# (golden.toml, laws.toml) into a fresh store and compares, bit for bit, every stored
# realization's physics digest (store_digest: every result field but the wall-clock ones) and
# `campaign analyze --json` with the files in expected/. Any change of the engine's or the
# analysis's bits fails it.
#   EXE=build/src/cli/campaign DIGEST=build/tests/campaign/store_digest tests/golden/golden.sh
#   ... golden.sh --bless      rewrites expected/ (only for a change that is intended and validated)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
: "${EXE:?EXE=path to the campaign executable}" "${DIGEST:?DIGEST=path to store_digest}"
PY=${PY:-/usr/bin/python3}
work=${WORK:-$(mktemp -d)}
rm -rf "$work" && mkdir -p "$work"
bless=0
[ "${1:-}" = "--bless" ] && bless=1

fail=0
total=0
for sweep in "$here"/*.toml; do
  name=$(basename "$sweep" .toml)
  HOPPER_PLOTS=0 "$EXE" run "$sweep" --store "$work/$name.h5" --threads 2 --no-plots \
    > "$work/$name.run.log" 2>&1 || { echo "golden: campaign run of $name.toml failed"; tail -20 "$work/$name.run.log"; exit 1; }
  "$DIGEST" "$work/$name.h5" > "$work/$name.digests.tsv"
  "$EXE" analyze "$work/$name.h5" --json --no-write > "$work/$name.analyze.raw.json"
  # The store's path is where this run wrote it: left out.
  "$PY" - "$work/$name.analyze.raw.json" "$work/$name.analyze.json" <<'PYEOF'
import json, sys
d = json.load(open(sys.argv[1]))
d.pop("store", None)
json.dump(d, open(sys.argv[2], "w"), indent=1, sort_keys=False)
open(sys.argv[2], "a").write("\n")
PYEOF
  total=$((total + $(wc -l < "$work/$name.digests.tsv")))
  if [ $bless = 1 ]; then
    cp "$work/$name.digests.tsv" "$work/$name.analyze.json" "$here/expected/"
    continue
  fi
  for f in $name.digests.tsv $name.analyze.json; do
    if ! diff -u "$here/expected/$f" "$work/$f" > "$work/$f.diff"; then
      echo "golden: $f differs from tests/golden/expected/$f:"
      head -40 "$work/$f.diff"
      fail=1
    fi
  done
done
if [ $bless = 1 ]; then
  echo "golden: blessed $total realizations and their analyses into $here/expected"
  exit 0
fi
if [ $fail = 0 ]; then
  echo "golden: $total realizations and the analyses bit for bit as blessed"
else
  echo "golden: bits changed. If the change is intended and validated (docs/development.md), re-bless:"
  echo "  EXE=$EXE DIGEST=$DIGEST $0 --bless"
fi
exit $fail
