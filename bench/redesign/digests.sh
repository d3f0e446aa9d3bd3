#!/usr/bin/env bash
# Digests of a few small campaigns run by one `campaign` binary (issue 17: a redesign must not
# change results). Prints, per campaign, the sha256 of the store's physics content
# (digests.py) and of `campaign analyze --json`. Compare two builds:
#   bench/redesign/digests.sh OLD/campaign /tmp/old > old.txt
#   bench/redesign/digests.sh NEW/campaign /tmp/new > new.txt && diff old.txt new.txt
set -euo pipefail
bin=$(realpath "$1"); out=$2
here=$(cd "$(dirname "$0")" && pwd); root=$(cd "$here/../.." && pwd)
rm -rf "$out"; mkdir -p "$out"; cd "$out"  # relative store paths: the JSON names the store
for sweep in "$root/campaigns/tiny.toml" "$root/campaigns/quickstart.toml" "$here/fields.toml" "$here/steady.toml"; do
  name=$(basename "$sweep" .toml)
  "$bin" run "$sweep" --store "$name.h5" --threads 1 --no-plots >"$name.log" 2>&1 ||
    { echo "digests: $name failed (see $out/$name.log)" >&2; exit 1; }
  "$bin" analyze "$name.h5" --json >"$name.json"
  echo "$name store $(/usr/bin/python3 "$here/digests.py" "$name.h5" | cut -d' ' -f1)"
  echo "$name store-results $(/usr/bin/python3 "$here/digests.py" --part results "$name.h5" | cut -d' ' -f1)"
  echo "$name analyze-json $(sha256sum <"$name.json" | cut -d' ' -f1)"
  # The same JSON parsed and written again (keys sorted): equal when the numbers read back as the
  # same doubles, whatever their formatting.
  echo "$name analyze-json-values $(/usr/bin/python3 -c 'import json,sys; print(json.dumps(json.load(sys.stdin), sort_keys=True))' <"$name.json" | sha256sum | cut -d' ' -f1)"
done
