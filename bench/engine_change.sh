#!/bin/bash
# bench/engine_change.sh OLD_BENCH NEW_BENCH OUTDIR [SEEDS]
# Runs bench_engine_change of two builds (old, new) on both scenes and both settings, the two
# builds alternating per scene and setting, and compares them (bench/engine_change_compare.py).
# Issue 25, part 2; docs/performance.md, "Statistical validation of the new formulation".
set -euo pipefail
old=$1 new=$2 out=$3 seeds=${4:-32}
mkdir -p "$out"
: >"$out/old.jsonl"
: >"$out/new.jsonl"
for scene in discharge jamming; do
    for setting in published default; do
        "$old" --scene $scene --setting $setting --seeds "$seeds" >>"$out/old.jsonl"
        "$new" --scene $scene --setting $setting --seeds "$seeds" >>"$out/new.jsonl"
    done
done
/usr/bin/python3 "$(dirname "$0")/engine_change_compare.py" "$out/old.jsonl" "$out/new.jsonl" --md "$out/table.md"
