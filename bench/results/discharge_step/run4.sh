#!/bin/bash
# Issue 41, fourth batch: the jamming scene again (the same seeds 401-528, the same bits) with
# the shakes recorded (bench_engine_change's shakes and multi_shake), gear4 delta 50 against
# corrected Verlet at 25; published model on core 0, calibrated on core 1, at once.
# Usage: run4.sh BENCH_ENGINE_CHANGE
set -euo pipefail
b=$1
side() { # core setting prefix
    local common=(--scene jamming --setting "$2" --first 401 --seeds 128)
    nice -n 5 taskset -c "$1" "$b" "${common[@]}" >"$3-base.jsonl"
    nice -n 5 taskset -c "$1" "$b" "${common[@]}" --scheme verlet --corrections 1 --delta 25 >"$3-v25c.jsonl"
}
side 0 published shk &
side 1 calibrated shk-cal &
wait
echo finished >&2
