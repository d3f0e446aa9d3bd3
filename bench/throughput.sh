#!/usr/bin/env bash
# Master throughput (issue 44, part 2; not run by ctest): results per second one master
# receives, journals (fdatasync), writes into the HDF5 view and answers with the next task, with
# K workers that return a canned result at once (bench_dispatch), as in-process threads
# (campaign run --threads K) and as oversubscribed MPI ranks (mpirun -np K+1). The master's rate
# R bounds the workers it keeps busy: a realization of L seconds needs R x L >= workers.
#
# usage: bench/throughput.sh [K ...]        (default: 1 8 64)
# env:   BUILD=build  OUT=/tmp/hopper-throughput  TASKS=2000  POINTS=20  REPEATS=3  MPI=1
# Prints one line per run and a table of medians (results/s, the master's CPU share) and, for
# realizations of 1 s, 1 min and 5 min, the workers the median rate of the most workers feeds.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
BUILD=${BUILD:-$root/build}
OUT=${OUT:-/tmp/hopper-throughput}
TASKS=${TASKS:-2000}
POINTS=${POINTS:-20}
REPEATS=${REPEATS:-3}
MPI=${MPI:-1}
bench=$BUILD/bench/bench_dispatch
workers=("$@")
[ ${#workers[@]} -gt 0 ] || workers=(1 8 64)
mkdir -p "$OUT"
log=$OUT/throughput.txt
: >"$log"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

one() {  # one CHANNEL K CMD...
    local channel=$1 k=$2 line
    shift 2
    line=$("$@" | grep '^dispatch:')
    echo "$channel $k $(cut -d' ' -f1 /proc/loadavg) $line" | tee -a "$log"
}

for k in "${workers[@]}"; do
    for ((r = 1; r <= REPEATS; r++)); do
        one threads "$k" "$bench" --tasks "$TASKS" --points "$POINTS" --threads "$k" \
            --dir "$OUT/threads"
        if [ "$MPI" = 1 ]; then
            one mpi "$k" mpirun --oversubscribe -np $((k + 1)) "$bench" --tasks "$TASKS" \
                --points "$POINTS" --dir "$OUT/mpi"
        fi
    done
done
rm -rf "$OUT/threads" "$OUT/mpi"
/usr/bin/python3 - "$log" <<'PY'
import collections, re, statistics, sys
rate = collections.defaultdict(list)
cpu = collections.defaultdict(list)
loads = []
for line in open(sys.argv[1]):
    ch, k, load = line.split()[:3]
    loads.append(float(load))
    rate[(ch, int(k))].append(float(re.search(r"= ([0-9.e+]+) results/s", line).group(1)))
    share = re.search(r"master CPU ([0-9.]+)%", line)
    cpu[(ch, int(k))].append(float(share.group(1)) if share else float("nan"))
print("| workers | channel | results/s (median) | runs | master CPU (% of wall) |")
print("|---|---|---|---|---|")
for key in sorted(rate, key=lambda x: (x[1], x[0])):
    v = rate[key]
    print(f"| {key[1]} | {key[0]} | {statistics.median(v):.0f} (range {min(v):.0f}-{max(v):.0f})"
          f" | {len(v)} | {statistics.median(cpu[key]):.0f} |")
print(f"\nload average (1 min) during the runs: {min(loads):.1f}-{max(loads):.1f}")
for ch in sorted({c for c, _ in rate}):
    k = max(n for c, n in rate if c == ch)
    r = statistics.median(rate[(ch, k)])
    print(f"{ch}, {k} workers: {r:.0f} results/s feeds " +
          ", ".join(f"{r * s:.0f} workers at {name}" for name, s in
                    (("1 s", 1), ("1 min", 60), ("5 min", 300))))
PY
