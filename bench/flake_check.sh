#!/bin/bash
# Flake check (issue 45): runs the timing-exposed test labels N times in a row and counts the
# failures per test, optionally with the machine loaded or ctest pinned to one core. Not part of
# the test suite (it takes N runs of several minutes each); see docs/development.md.
#
# usage: bench/flake_check.sh BUILD_DIR N [--load] [--pinned] [--labels REGEX] [--jobs J]
#                             [--out DIR] [-- CTEST_ARGS...]
#   --load          one busy loop per core at nice 19 for the whole check (killed at its end):
#                   the tests compete for every core with a job that never sleeps
#   --pinned        ctest, and so every test and process it starts, on core 0 alone (taskset)
#   --labels REGEX  the ctest label expression (default 'campaign|mpi|slurm|cli')
#   --jobs J        ctest -j J (default: the number of cores)
#   --out DIR       where each run's ctest output goes (default: a new directory under /tmp)
#   CTEST_ARGS      passed to ctest after the label (e.g. -R 'checkpoint' --repeat until-fail:5)
# Prints each run's wall time and failed tests, then the counts: runs, runs with a failure,
# failures per test. Exits 0 when no run failed, 1 when one did, 2 on a usage error.
# The slurm label needs root (the tests bring up a local single-node Slurm); without it they
# skip (exit 77, counted by ctest as not run, not as failures).
set -u
usage() {
    sed -n '6,18p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
}
[ $# -ge 2 ] || usage
BUILD=$1
N=$2
shift 2
[ -d "$BUILD" ] && [ -f "$BUILD/CTestTestfile.cmake" ] || { echo "flake_check: $BUILD is not a build directory" >&2; exit 2; }
[[ $N =~ ^[1-9][0-9]*$ ]] || { echo "flake_check: N must be a positive number, got '$N'" >&2; exit 2; }
LOAD=0
PINNED=0
LABELS='campaign|mpi|slurm|cli'
JOBS=$(nproc)
OUT=""
EXTRA=()
while [ $# -gt 0 ]; do
    case $1 in
    --load) LOAD=1 ;;
    --pinned) PINNED=1 ;;
    --labels) LABELS=${2:?--labels needs a value}; shift ;;
    --jobs) JOBS=${2:?--jobs needs a value}; shift ;;
    --out) OUT=${2:?--out needs a value}; shift ;;
    --) shift; EXTRA=("$@"); break ;;
    *) echo "flake_check: unknown option '$1'" >&2; usage ;;
    esac
    shift
done
[ -n "$OUT" ] || OUT=$(mktemp -d /tmp/flake_check.XXXXXX)
mkdir -p "$OUT" || exit 2

LOADERS=()
stop_load() {
    local p
    for p in "${LOADERS[@]}"; do kill "$p" 2>/dev/null; done
    for p in "${LOADERS[@]}"; do wait "$p" 2>/dev/null; done
    LOADERS=()
}
trap stop_load EXIT
trap 'stop_load; exit 130' INT TERM
if [ $LOAD -eq 1 ]; then
    for _ in $(seq 1 "$(nproc)"); do
        nice -n 19 bash -c 'while :; do :; done' &
        LOADERS+=($!)
    done
fi
RUNNER=()
[ $PINNED -eq 1 ] && RUNNER=(taskset -c 0)

mode="$([ $LOAD -eq 1 ] && echo "loaded ($(nproc) busy loops at nice 19)" || echo "no added load")"
mode="$mode, $([ $PINNED -eq 1 ] && echo "pinned to core 0" || echo "not pinned")"
echo "flake_check: $N run(s) of ctest -L '$LABELS' -j $JOBS${EXTRA[*]:+ ${EXTRA[*]}} in $BUILD; $mode"
echo "flake_check: load average before: $(cut -d' ' -f1-3 /proc/loadavg); outputs in $OUT"

declare -A FAILS=()
failed_runs=0
t_all=$SECONDS
for run in $(seq 1 "$N"); do
    log=$OUT/run$run.log
    t0=$(date +%s.%N)
    "${RUNNER[@]}" ctest --test-dir "$BUILD" -L "$LABELS" -j "$JOBS" --output-on-failure \
        "${EXTRA[@]}" >"$log" 2>&1
    rc=$?
    wall=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.0f", b - a }')
    # ctest's summary: "The following tests FAILED:" then "\t<n> - <name> (<why>)" per test.
    failed=$(sed -n '/^The following tests FAILED:/,$ s/^[[:space:]]*[0-9]\+ - \([^ ]*\) (\(.*\))$/\1 (\2)/p' "$log")
    summary=$(grep -E '^[0-9]+% tests passed' "$log" | tail -1)
    if [ -n "$failed" ] || [ "$rc" -ne 0 ]; then
        failed_runs=$((failed_runs + 1))
        [ -n "$failed" ] || failed="(ctest exited $rc without a list of failed tests: see $log)"
        echo "run $run: ${wall} s, ${summary:-no summary}; failed: $(echo "$failed" | paste -sd ';' | sed 's/;/; /g')"
        while read -r name _; do
            [ -n "$name" ] && FAILS[$name]=$((${FAILS[$name]:-0} + 1))
        done <<<"$failed"
    else
        echo "run $run: ${wall} s, ${summary:-no summary}"
    fi
done
echo "flake_check: $N run(s) in $((SECONDS - t_all)) s; $failed_runs with a failure"
if [ ${#FAILS[@]} -gt 0 ]; then
    echo "failures per test (of $N runs):"
    for name in "${!FAILS[@]}"; do printf '  %3d  %s\n' "${FAILS[$name]}" "$name"; done | sort -k2
fi
[ $failed_runs -eq 0 ]
