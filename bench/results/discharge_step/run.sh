#!/bin/bash
# Issue 41: the discharge's time step (the whole run's delta) and the integrator, validated
# against the published setting (gear4, delta 50, no corrections) on the small scenes of
# bench_engine_change, fresh seeds (jamming 401-528, discharge 401-464), each scene in two
# chunks, the variants in turn. Usage: run.sh BENCH_ENGINE_CHANGE CORE VARIANT...
# with VARIANT one of base g35 g30 v35c v30c v25c; writes VARIANT.jsonl. Run as
#   run.sh B 1 base g35 v35c g30  &  run.sh B 0 v25c v30c
# Compare with /usr/bin/python3 bench/engine_change_compare.py base.jsonl VARIANT.jsonl
set -euo pipefail
b=$1 core=$2
shift 2
args() {
    case $1 in
        base) ;;
        g35) echo --delta 35 ;;
        g30) echo --delta 30 ;;
        v35c) echo --scheme verlet --corrections 1 --delta 35 ;;
        v30c) echo --scheme verlet --corrections 1 --delta 30 ;;
        v25c) echo --scheme verlet --corrections 1 --delta 25 ;;
        *) echo "unknown variant $1" >&2; exit 2 ;;
    esac
}
for scene in jamming discharge; do
    if [ $scene = jamming ]; then n=128; else n=64; fi
    for chunk in 0 1; do
        half=$((n / 2)) f0=$((401 + chunk * n / 2))
        for v in "$@"; do
            read -r -a extra <<<"$(args "$v")"
            nice -n 5 taskset -c "$core" "$b" --scene $scene --setting published --first $f0 \
                --seeds $half "${extra[@]}" >>"$v.jsonl"
        done
    done
done
echo finished >&2
