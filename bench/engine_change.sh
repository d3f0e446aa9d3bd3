#!/bin/bash
# bench/engine_change.sh OLD_BENCH NEW_BENCH OUTDIR [SEEDS]
# Runs bench_engine_change of two builds (old, new) on both scenes and both settings, the two
# builds alternating per scene and setting, and compares them (bench/engine_change_compare.py).
# Issue 25, part 2; docs/performance.md, "Statistical validation of the new formulation".
# OLD_ARGS and NEW_ARGS (environment, split at blanks) go to the one side's every run: one build
# against itself at two settings, e.g. NEW_ARGS="--settle-ke 1e-3" (issue 41).
set -euo pipefail
old=$1 new=$2 out=$3 seeds=${4:-32}
read -r -a old_args <<<"${OLD_ARGS:-}"
read -r -a new_args <<<"${NEW_ARGS:-}"
mkdir -p "$out"
: >"$out/old.jsonl"
: >"$out/new.jsonl"
for scene in discharge jamming; do
    for setting in published default; do
        "$old" --scene $scene --setting $setting --seeds "$seeds" "${old_args[@]}" >>"$out/old.jsonl"
        "$new" --scene $scene --setting $setting --seeds "$seeds" "${new_args[@]}" >>"$out/new.jsonl"
    done
done
/usr/bin/python3 "$(dirname "$0")/engine_change_compare.py" "$out/old.jsonl" "$out/new.jsonl" --md "$out/table.md"
