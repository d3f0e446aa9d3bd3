#!/bin/bash
# Issue 41, second batch: corrected velocity Verlet at delta 30 and 25 on the seeds of run.sh.
# Usage: run2.sh BENCH_ENGINE_CHANGE CORE
set -euo pipefail
b=$1 core=${2:-0}
run() { # file args...
    local f=$1; shift
    nice -n 5 taskset -c "$core" "$b" "$@" >>"$f"
}
for scene in jamming discharge; do
    if [ $scene = jamming ]; then n=128 first=401; else n=64 first=401; fi
    for chunk in 0 1; do
        half=$((n / 2)); f0=$((first + chunk * half))
        common=(--scene $scene --setting published --first $f0 --seeds $half)
        run v25c.jsonl "${common[@]}" --scheme verlet --corrections 1 --delta 25
        run v30c.jsonl "${common[@]}" --scheme verlet --corrections 1 --delta 30
    done
done
echo finished >&2
