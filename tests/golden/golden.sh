#!/usr/bin/env bash
# Golden regression check (issue 28; tests/golden/README.md): runs golden.toml into a fresh store
# and compares, bit for bit, every stored realization's physics digest (store_digest: every
# result field but the wall-clock ones) and `campaign analyze --json` with the files in
# expected/. Any change of the engine's or the analysis's bits fails it.
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

HOPPER_PLOTS=0 "$EXE" run "$here/golden.toml" --store "$work/golden.h5" --threads 2 --no-plots \
  > "$work/run.log" 2>&1 || { echo "golden: campaign run failed"; tail -20 "$work/run.log"; exit 1; }
"$DIGEST" "$work/golden.h5" > "$work/digests.tsv"
"$EXE" analyze "$work/golden.h5" --json --no-write > "$work/analyze.raw.json"
# The store's path is where this run wrote it: left out.
"$PY" - "$work/analyze.raw.json" "$work/analyze.json" <<'PYEOF'
import json, sys
d = json.load(open(sys.argv[1]))
d.pop("store", None)
json.dump(d, open(sys.argv[2], "w"), indent=1, sort_keys=False)
open(sys.argv[2], "a").write("\n")
PYEOF

if [ $bless = 1 ]; then
  cp "$work/digests.tsv" "$work/analyze.json" "$here/expected/"
  echo "golden: blessed $(wc -l < "$here/expected/digests.tsv") realizations and the analysis into $here/expected"
  exit 0
fi
fail=0
for f in digests.tsv analyze.json; do
  if ! diff -u "$here/expected/$f" "$work/$f" > "$work/$f.diff"; then
    echo "golden: $f differs from tests/golden/expected/$f:"
    head -40 "$work/$f.diff"
    fail=1
  fi
done
n=$(wc -l < "$work/digests.tsv")
if [ $fail = 0 ]; then
  echo "golden: $n realizations and the analysis bit for bit as blessed"
else
  echo "golden: bits changed. If the change is intended and validated (docs/development.md), re-bless:"
  echo "  EXE=$EXE DIGEST=$DIGEST $0 --bless"
fi
exit $fail
