#!/usr/bin/env bash
# Scale benchmark of the master and the store (issue 44, part 1; not run by ctest): synthetic
# campaigns of N realizations (N/PER_POINT points x PER_POINT realizations each) whose results
# are injected by bench_dispatch's canned runner (no physics), then the wall time and peak
# memory (/usr/bin/time) of every operation a user runs on such a store:
#
#   run              bench_dispatch: the whole campaign from nothing (THREADS worker threads)
#   resume_finished  bench_dispatch --keep on the finished store: journal replay, nothing to run
#   resume_killed    bench_dispatch --keep on the store cut in the middle of its last result
#                    record (as kill -9 leaves it; the run-end and sync records after it go too)
#                    without its HDF5 file (a killed run's file is not in step and is rebuilt all
#                    the same): journal replay, torn tail dropped, HDF5 file rebuilt, the one
#                    missing realization run
#   status           campaign status STORE
#   analyze          campaign analyze STORE (tables, /analysis written; skipped above
#                    ANALYZE_MAX: about 2.7 kB per realization of what the statistics read)
#   export           campaign export STORE --csv DIR (skipped above EXPORT_MAX realizations)
#   open_store       Python: open_store(STORE) and its points, realizations and survival tables
#                    (skipped above OPEN_MAX)
#
# usage: bench/scale.sh [N ...]          (default: 1000 10000 100000)
# env:   BUILD=build  OUT=/tmp/hopper-scale  PER_POINT=100  THREADS=8  REPEATS=3
#        RUN_REPEATS=REPEATS (the run is the slow one)  EXPORT_MAX=100000  ANALYZE_MAX=100000
#        OPEN_MAX=1000000  KEEP=0 (1: keep the stores)
# Writes OUT/scale.csv (one row per operation, size and repeat: wall time, CPU time = user +
# system of the process and its children, max RSS, the load average) and prints the table of
# medians with the growth exponent of each operation (bench/scale_table.py; --png draws the
# figure). On a shared machine the CPU time is the steadier measure: wall time includes waiting
# for a core.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
BUILD=${BUILD:-$root/build}
OUT=${OUT:-/tmp/hopper-scale}
PER_POINT=${PER_POINT:-100}
THREADS=${THREADS:-8}
REPEATS=${REPEATS:-3}
RUN_REPEATS=${RUN_REPEATS:-$REPEATS}
EXPORT_MAX=${EXPORT_MAX:-100000}
ANALYZE_MAX=${ANALYZE_MAX:-100000}
OPEN_MAX=${OPEN_MAX:-1000000}
KEEP=${KEEP:-0}
bench=$BUILD/bench/bench_dispatch
campaign=$BUILD/src/cli/campaign
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(1000 10000 100000)
mkdir -p "$OUT"
csv=$OUT/scale.csv
[ -s "$csv" ] || echo "operation,realizations,points,repeat,wall_s,cpu_s,max_rss_kb,load1" >"$csv"
export HOPPER_CAMPAIGN=$campaign HOPPER_PLOTS=0

# measure OP N P REPEAT CMD...: one timed run appended to the CSV (the command's output dropped).
measure() {
    local op=$1 n=$2 p=$3 rep=$4
    shift 4
    local t
    t=$(mktemp)
    if ! /usr/bin/time -f "%e %U %S %M" -o "$t" "$@" >"$OUT/last.out" 2>"$OUT/last.err"; then
        echo "scale.sh: $op at $n failed:" >&2
        tail -5 "$OUT/last.err" >&2
        rm -f "$t"
        return 1
    fi
    read -r wall user sys rss <"$t"
    rm -f "$t"
    cpu=$(echo "$user + $sys" | bc -l)
    echo "$op,$n,$p,$rep,$wall,$cpu,$rss,$(cut -d' ' -f1 /proc/loadavg)" >>"$csv"
    printf '%-16s N=%-8s %8.2f s wall %8.2f s CPU %8.1f MB\n' "$op" "$n" "$wall" "$cpu" \
        "$(echo "$rss/1024" | bc -l)"
}

# Cuts the journal after its last result record's first half: what a kill -9 in the middle of
# writing that record leaves (the run-end and sync records after it go too).
tear_journal() {
    /usr/bin/python3 - "$1" <<'PY'
import struct, sys
with open(sys.argv[1], "r+b") as f:  # record headers only: the journal may be gigabytes
    pos, last = 16, None
    while True:
        f.seek(pos)
        head = f.read(16)
        if len(head) < 16:
            break
        length = struct.unpack_from("<I", head, 8)[0]
        if head[4] == 2:
            last = (pos, length)
        pos += 16 + length
    at, length = last
    f.truncate(at + (16 + length) // 2)
PY
}

open_store_py="
import sys
sys.path.insert(0, '$root/analysis')
from hopper_store import open_store
with open_store(sys.argv[1]) as s:
    n = len(s.points), len(s.realizations), len(s.survival)
print(n)
"

for n in "${sizes[@]}"; do
    p=$((n / PER_POINT))
    [ "$p" -ge 1 ] || p=1
    dir=$OUT/n$n
    for ((r = 1; r <= RUN_REPEATS; r++)); do
        measure run "$n" "$p" "$r" "$bench" --tasks "$n" --points "$p" --threads "$THREADS" \
            --dir "$dir"
    done
    for ((r = 1; r <= REPEATS; r++)); do
        measure resume_finished "$n" "$p" "$r" "$bench" --tasks "$n" --points "$p" \
            --threads "$THREADS" --dir "$dir" --keep
    done
    for ((r = 1; r <= REPEATS; r++)); do
        measure status "$n" "$p" "$r" "$campaign" status "$dir/dispatch.h5"
    done
    if [ "$n" -le "$ANALYZE_MAX" ]; then
        for ((r = 1; r <= REPEATS; r++)); do
            measure analyze "$n" "$p" "$r" "$campaign" analyze "$dir/dispatch.h5"
        done
    fi
    if [ "$n" -le "$EXPORT_MAX" ]; then
        for ((r = 1; r <= REPEATS; r++)); do
            rm -rf "$dir/csv"
            measure export "$n" "$p" "$r" "$campaign" export "$dir/dispatch.h5" --csv "$dir/csv"
        done
        rm -rf "$dir/csv"
    fi
    if [ "$n" -le "$OPEN_MAX" ]; then
        for ((r = 1; r <= REPEATS; r++)); do
            measure open_store "$n" "$p" "$r" /usr/bin/python3 -c "$open_store_py" \
                "$dir/dispatch.h5"
        done
    fi
    # Last, on the store itself (no copy: a 10^6 store's journal is 6.6 GB): torn, resumed,
    # whole again, torn again.
    for ((r = 1; r <= REPEATS; r++)); do
        tear_journal "$dir/dispatch.h5.journal"
        rm -f "$dir/dispatch.h5"
        measure resume_killed "$n" "$p" "$r" "$bench" --tasks "$n" --points "$p" \
            --threads "$THREADS" --dir "$dir" --keep
        grep -q "^dispatch: 1 of $n results" "$OUT/last.out" || {
            echo "scale.sh: the resume did not run exactly one realization:" >&2
            cat "$OUT/last.out" >&2
            exit 1
        }
    done
    [ "$KEEP" = 1 ] || rm -rf "$dir"
done
/usr/bin/python3 "$here/scale_table.py" "$csv"
