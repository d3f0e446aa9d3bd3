#!/bin/bash
# Issue 41, third batch: the calibrated model (issue 39; bench_engine_change --setting
# calibrated), gear4 delta 50 against corrected Verlet at 25, jamming scene, seeds 401-528;
# then the full published column (43 cm, 8750 disks, D 2.7 cm), settled only, seeds 1-12, with
# corrected Verlet at 25 (its gear4 delta 50 side: bench/results/settle_rule/old-big.jsonl).
# Usage: run3.sh BENCH_ENGINE_CHANGE CORE
set -euo pipefail
b=$1 core=${2:-0}
run() { # file args...
    local f=$1; shift
    nice -n 5 taskset -c "$core" "$b" "$@" >>"$f"
}
for chunk in 0 1; do
    common=(--scene jamming --setting calibrated --first $((401 + chunk * 64)) --seeds 64)
    run cal-base.jsonl "${common[@]}"
    run cal-v25c.jsonl "${common[@]}" --scheme verlet --corrections 1 --delta 25
done
run big-v25c.jsonl --scene discharge --setting published --width 43 --particles 8750 --D 2.7 \
    --settle-only 1 --seeds 12 --scheme verlet --corrections 1 --delta 25
echo finished >&2
