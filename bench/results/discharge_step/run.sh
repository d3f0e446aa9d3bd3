#!/bin/bash
# Issue 41: the discharge's time step (the whole run's delta) and the integrator, validated
# against the published setting (gear4, delta 50, no corrections) on the small scenes of
# bench_engine_change, fresh seeds. Usage: run.sh BENCH_ENGINE_CHANGE CORE
# Writes base.jsonl (published), and one file per variant; compare with
#   /usr/bin/python3 bench/engine_change_compare.py base.jsonl VARIANT.jsonl
set -euo pipefail
b=$1 core=${2:-1}
run() { # file args...
    local f=$1; shift
    nice -n 5 taskset -c "$core" "$b" "$@" >>"$f"
}
for scene in jamming discharge; do
    if [ $scene = jamming ]; then n=128 first=401; else n=64 first=401; fi
    for chunk in 0 1; do
        half=$((n / 2)); f0=$((first + chunk * half))
        common=(--scene $scene --setting published --first $f0 --seeds $half)
        run base.jsonl "${common[@]}"
        run g35.jsonl "${common[@]}" --delta 35
        run v35c.jsonl "${common[@]}" --scheme verlet --corrections 1 --delta 35
        run g30.jsonl "${common[@]}" --delta 30
    done
done
echo finished >&2
