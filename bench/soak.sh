#!/usr/bin/env bash
# Soak (issue 44, part 4; not run by ctest): hours of one campaign after another, each killed at
# random moments and resumed with the same command until it finishes, then compared with an
# uninterrupted run of the same sweep: every realization present exactly once and bit-identical.
#
# usage: bench/soak.sh [--build DIR] [--hours H] [--seed S] [--np N] [--out DIR]
#                      [--kill-min S] [--kill-max S] [--realizations R]
#   --build DIR        the build with src/cli/campaign and tests/campaign/store_digest (build)
#   --hours H          how long to keep killing (1); the cycle running at the end is finished
#                      without kills and checked like the others
#   --seed S           the seed of the kills' moments and kinds (bash's RANDOM; 1)
#   --np N             mpirun ranks (3: the master and two workers)
#   --kill-min/max S   a kill comes uniformly between these seconds after the job's start (20, 180)
#   --realizations R   per outlet of the soak's sweep (1000: 3 outlets, about 10 min of two
#                      workers on this project's VM, so that a cycle sees several kills)
#   --out DIR          where the stores, logs and soak.tsv go (/tmp/hopper-soak)
#
# The kinds of kill (each drawn with equal chance), as a cluster deals them:
#   worker   SIGKILL to one worker rank (Open MPI then ends the job)
#   master   SIGKILL to rank 0
#   node     SIGKILL to two ranks at once (every rank of a "node": the master's or the workers')
#   job      SIGKILL to every process of the job (mpirun included): a lost allocation
#   term     SIGTERM to every process of the job, as Slurm's time limit sends it: the run saves
#            its realizations' states
#   stop     SIGSTOP to the master for 5-20 s while the workers go on, then SIGCONT; the job is
#            not killed (it goes on to the next kill)
# Each kill is logged to OUT/soak.tsv (cycle, kill, kind, seconds after the start, exit code,
# realizations stored after it); each finished cycle to OUT/cycles.tsv (cycle, kills, runs,
# realizations, duplicates, digests equal to the reference). Exit 1 when any cycle lost,
# duplicated or changed a realization.
set -uo pipefail
BUILD=build HOURS=1 SEED=1 NP=3 OUT=/tmp/hopper-soak KMIN=20 KMAX=180 REAL=1000
while [ $# -gt 0 ]; do
    case $1 in
        --build) BUILD=$2; shift 2 ;;
        --hours) HOURS=$2; shift 2 ;;
        --seed) SEED=$2; shift 2 ;;
        --np) NP=$2; shift 2 ;;
        --out) OUT=$2; shift 2 ;;
        --kill-min) KMIN=$2; shift 2 ;;
        --kill-max) KMAX=$2; shift 2 ;;
        --realizations) REAL=$2; shift 2 ;;
        *) echo "soak.sh: unknown argument '$1' (see the header of bench/soak.sh)" >&2; exit 2 ;;
    esac
done
SRC=$(cd "$(dirname "$0")/.." && pwd)
EXE=$(realpath "$BUILD/src/cli/campaign") || { echo "soak.sh: no $BUILD/src/cli/campaign" >&2; exit 2; }
DIGEST=$(realpath "$BUILD/tests/campaign/store_digest") || { echo "soak.sh: no store_digest in $BUILD" >&2; exit 2; }
[ "$NP" -ge 3 ] || { echo "soak.sh: --np must be at least 3 (a master and two workers)" >&2; exit 2; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1 HOPPER_PLOTS=0
rm -rf "$OUT" && mkdir -p "$OUT" && cd "$OUT" || exit 2
RANDOM=$SEED

# The soak's sweep: tests/campaign/data/mini.toml's scene (100 disks, 0.1-0.3 s a realization)
# with more realizations.
sed "s/^realizations = .*/realizations = $REAL/; s/^name = .*/name = \"soak\"/" \
    "$SRC/tests/campaign/data/mini.toml" >soak.toml
TOTAL=$((3 * REAL))
RUN_OPTS=(--progress-interval 0 --flush-interval 1 --checkpoint-interval 5 --no-plots)

log() { echo "[$(date -u +%FT%TZ)] $*" | tee -a soak.log >&2; }
stored() { "$EXE" status "$1" --json 2>/dev/null | /usr/bin/python3 -c 'import json,sys; print(json.load(sys.stdin)["done"])' 2>/dev/null || echo "-"; }
rank_pid() {  # rank_pid JOB RANK: the campaign process of that MPI rank
    local p
    for p in $(pgrep -s "$1" -x campaign); do
        grep -qz "^OMPI_COMM_WORLD_RANK=$2\$" /proc/$p/environ 2>/dev/null && { echo "$p"; return; }
    done
}
rsleep() { sleep "$(( $1 + RANDOM % ($2 - $1 + 1) ))"; }

log "reference: $TOTAL realizations, uninterrupted, $((NP - 1)) worker ranks"
/usr/bin/time -f %e -o ref.time mpirun -np "$NP" "$EXE" run soak.toml --store ref.h5 "${RUN_OPTS[@]}" >ref.log 2>&1 ||
    { log "the reference run failed (ref.log)"; exit 1; }
"$DIGEST" ref.h5 >ref.digest || { log "store_digest failed on the reference"; exit 1; }
[ "$(wc -l <ref.digest)" -eq "$TOTAL" ] || { log "the reference holds $(wc -l <ref.digest) of $TOTAL"; exit 1; }
log "reference: $(cat ref.time) s"

printf 'cycle\tkill\tkind\tafter_s\texit\tstored\n' >soak.tsv
printf 'cycle\tkills\truns\trealizations\tduplicates\tidentical\tseconds\n' >cycles.tsv
END=$((SECONDS + $(/usr/bin/python3 -c "print(int(float('$HOURS') * 3600))")))
KINDS=(worker master node job term stop)
bad=0 cycle=0 all_kills=0
while [ "$SECONDS" -lt "$END" ]; do
    cycle=$((cycle + 1)) kills=0 runs=0 c0=$SECONDS
    STORE=c$cycle.h5
    while :; do
        runs=$((runs + 1))
        setsid mpirun -np "$NP" "$EXE" run soak.toml --store "$STORE" "${RUN_OPTS[@]}" >>c$cycle.log 2>&1 &
        JOB=$! t0=$SECONDS
        # Past the end: no more kills, the run finishes the cycle.
        while [ "$SECONDS" -lt "$END" ] && kill -0 "$JOB" 2>/dev/null; do
            wait_s=$((KMIN + RANDOM % (KMAX - KMIN + 1)))
            while [ $((SECONDS - t0)) -lt "$wait_s" ] && kill -0 "$JOB" 2>/dev/null; do sleep 1; done
            kill -0 "$JOB" 2>/dev/null || break
            kind=${KINDS[RANDOM % ${#KINDS[@]}]}
            after=$((SECONDS - t0))
            case $kind in
                worker) victims=$(rank_pid "$JOB" $((1 + RANDOM % (NP - 1)))) ;;
                master) victims=$(rank_pid "$JOB" 0) ;;
                node) if [ $((RANDOM % 2)) -eq 0 ]; then victims="$(rank_pid "$JOB" 0) $(rank_pid "$JOB" 1)"
                      else victims="$(rank_pid "$JOB" $((NP - 2))) $(rank_pid "$JOB" $((NP - 1)))"; fi ;;
                job) victims=$(ps -o pid= -s "$JOB" | tr '\n' ' ') ;;
                term) victims=$(ps -o pid= -s "$JOB" | tr '\n' ' ') ;;
                stop) victims=$(rank_pid "$JOB" 0) ;;
            esac
            case $kind in
                term) kill -TERM $victims 2>/dev/null ;;
                stop) kill -STOP $victims 2>/dev/null; rsleep 5 20; kill -CONT $victims 2>/dev/null ;;
                *) kill -KILL $victims 2>/dev/null ;;
            esac
            kills=$((kills + 1)) all_kills=$((all_kills + 1))
            if [ "$kind" = stop ]; then
                printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$cycle" "$kills" stop "$after" - - >>soak.tsv
                t0=$SECONDS  # the next kill of this run is timed from here
                continue
            fi
            break
        done
        wait "$JOB" 2>/dev/null
        rc=$?
        # mpirun ends the other ranks; none may outlive the job.
        for _ in $(seq 60); do [ -z "$(pgrep -s "$JOB")" ] && break; sleep 1; done
        if [ -n "$(pgrep -s "$JOB")" ]; then
            log "cycle $cycle: processes outlived the job: $(pgrep -s "$JOB" | tr '\n' ' '); killed"
            kill -KILL $(pgrep -s "$JOB") 2>/dev/null
            bad=1
        fi
        [ "$rc" -eq 0 ] && break
        printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$cycle" "$kills" "$kind" "$after" "$rc" "$(stored "$STORE")" >>soak.tsv
        log "cycle $cycle: $kind after ${after}s, exit $rc, $(stored "$STORE") of $TOTAL stored"
        [ "$runs" -lt 200 ] || { log "cycle $cycle: 200 runs without finishing"; bad=1; break; }
    done
    dups=0 same=no
    if "$DIGEST" "$STORE" >c$cycle.digest 2>c$cycle.digest.err; then
        dups=$(cut -f1,2 c$cycle.digest | sort | uniq -d | wc -l)
        cmp -s ref.digest c$cycle.digest && same=yes
    else
        dups="store_digest: $(head -c 200 c$cycle.digest.err)"
    fi
    n=$(wc -l <c$cycle.digest)
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$cycle" "$kills" "$runs" "$n" "$dups" "$same" $((SECONDS - c0)) >>cycles.tsv
    log "cycle $cycle done: $kills kills, $runs runs, $n of $TOTAL realizations, identical to the reference: $same"
    [ "$same" = yes ] || bad=1
    [ "$same" = yes ] && rm -rf "$STORE" "$STORE".*  # keep the disk small; failures are kept
done
log "soak over: $cycle cycles, $all_kills kills in $((SECONDS / 60)) min; $( [ $bad -eq 0 ] && echo 'every cycle identical to the reference' || echo 'FAILURES: see cycles.tsv')"
exit $bad
