#!/bin/bash
# Issue 44, part 3: a worker killed by the kernel for memory. Both worker ranks of a 3-rank job
# run under a memory limit that mini.toml's scene fits in and a 400 000-disk point does not; the
# kernel kills a worker (SIGKILL) as it outgrows the limit, and Open MPI ends the whole job.
# Resumed with the same command, a realization that kills its worker would kill every job that
# hands it out: each run journals what it hands out, a run that dies counts a death for each
# realization it was running, and at --max-deaths (3) a realization is set aside (recorded as an
# error with the reason, not handed out again). Checked: the job is resumed until it ends by
# itself (exit 3, within 9 runs), the 4 big realizations set aside with the reason, the other 12
# stored bit-identical to an uninterrupted run's, nothing lost or stored twice.
#
# The limit is a memory cgroup (v1 or v2, where the test may create one: the real OOM killer);
# elsewhere a watcher stands in for the kernel: it SIGKILLs a worker rank whose resident memory
# passes the limit (what the OOM killer does; it says which one ran; HOPPER_TEST_NO_CGROUP=1
# chooses it everywhere).
source "$(dirname "$0")/lib.sh"
reference

MEM=$WORK/mem.toml
big_point_sweep "$MEM"
LIMIT_MB=150  # a worker rank of mini.toml needs about 40 MB

CG=""
cleanup() {
    [ -n "$WATCHER" ] && kill "$WATCHER" 2>/dev/null
    if [ -n "$CG" ] && [ -d "$CG" ]; then
        for p in $(cat "$CG/cgroup.procs" 2>/dev/null); do kill -9 "$p" 2>/dev/null; done
        sleep 0.2
        rmdir "$CG" 2>/dev/null
    fi
}
WATCHER=""
trap cleanup EXIT
name=hopper-oom-test-$$
if [ -n "${HOPPER_TEST_NO_CGROUP:-}" ]; then  # the watcher even where a cgroup could be made
    :
elif mkdir /sys/fs/cgroup/memory/$name 2>/dev/null; then  # cgroup v1
    CG=/sys/fs/cgroup/memory/$name
    echo $((LIMIT_MB << 20)) >"$CG/memory.limit_in_bytes" || CG=""
    echo 0 >"$CG/memory.swappiness" 2>/dev/null
    echo 0 >"$CG/memory.memsw.limit_in_bytes" 2>/dev/null
elif grep -qw memory /sys/fs/cgroup/cgroup.subtree_control 2>/dev/null &&
    mkdir /sys/fs/cgroup/$name 2>/dev/null; then  # cgroup v2
    CG=/sys/fs/cgroup/$name
    echo $((LIMIT_MB << 20)) >"$CG/memory.max" && echo 0 >"$CG/memory.swap.max" 2>/dev/null || true
    [ -w "$CG/memory.max" ] || CG=""
fi
if [ -n "$CG" ]; then
    echo "the limit: a memory cgroup of $LIMIT_MB MB ($CG), the kernel's OOM killer"
else
    echo "the limit: no memory cgroup (none can be made here, or HOPPER_TEST_NO_CGROUP is set); a watcher kills a worker rank above $LIMIT_MB MB resident"
    (
        while sleep 0.05; do
            for p in $(pgrep -f "campaign run $MEM"); do
                grep -qz '^OMPI_COMM_WORLD_RANK=0$' /proc/$p/environ 2>/dev/null && continue
                grep -qz '^OMPI_COMM_WORLD_RANK=' /proc/$p/environ 2>/dev/null || continue
                kb=$(awk '/^VmRSS/ {print $2}' /proc/$p/status 2>/dev/null)
                [ -n "$kb" ] && [ "$kb" -gt $((LIMIT_MB * 1024)) ] && kill -9 "$p" 2>/dev/null
            done
        done
    ) &
    WATCHER=$!
fi
WRAP=$WORK/worker.sh  # a worker rank joins the cgroup, then becomes the campaign process
cat >"$WRAP" <<SH
#!/bin/bash
[ -n "$CG" ] && echo \$\$ >"$CG/cgroup.procs"
exec "$EXE" "\$@"
SH
chmod +x "$WRAP"

runs=0
rc=137
while [ "$rc" -ne 3 ]; do
    runs=$((runs + 1))
    [ "$runs" -le 9 ] || fail "still not done after 9 runs (last exit $rc)"
    mpirun -np 1 "$EXE" run "$MEM" --store mem.h5 --progress-interval 0 \
        : -np 2 "$WRAP" run "$MEM" --store mem.h5 --progress-interval 0 >run$runs.out 2>run$runs.err
    rc=$?
    case $rc in
    3) ;;
    0 | 2 | 1) cat run$runs.err >&2; fail "run $runs exited $rc" ;;
    *) echo "run $runs: the job died (exit $rc): $(grep -c . run$runs.err) lines on stderr" ;;
    esac
done
[ "$runs" -ge 4 ] || fail "the job died only $((runs - 1)) times: no worker was killed for memory"
expect_in run$runs.err "realization(s) set aside"
"$EXE" status mem.h5 --json >mem.json || fail "status of mem.h5"
"$EXE" status mem.h5 >status.txt || fail "status of mem.h5"
expect_in status.txt "were running when their job died"
"$PY" - mem.json <<'PY' || fail "the store after the memory kills"
import json, sys
s = json.load(open(sys.argv[1]))
assert (s["total"], s["done"], s["failed"], s["pending"], s["died"]) == (16, 12, 4, 0, 4), s
big = [f for f in s["failures"] if "hopper.particles=4e+05" in f["label"]]
assert len(big) == 4 and len(s["failures"]) == 4, s["failures"]
for f in big:
    assert f["reason"].startswith("set aside: the job died each of the 3 times"), f
    assert "--max-deaths 4" in f["reason"], f
died = [r["running_when_died"] for r in s["runs"] if r["end_reason"] is None]
assert len(died) == len(s["runs"]) - 1 and all(n >= 1 for n in died), s["runs"]
print("runs", len(s["runs"]), "; realizations running when each died:", died)
print("set aside:", big[0]["reason"][:90], "...")
PY
"$DIGEST" mem.h5 | grep -v "hopper.particles=4e+05" >mem.digest || fail "store_digest mem.h5"
same_digests "$WORK/ref.digest" mem.digest
# With a higher limit the set-aside realizations are handed out again (and die again here).
mpirun -np 1 "$EXE" run "$MEM" --store mem.h5 --progress-interval 0 --max-deaths 4 \
    : -np 2 "$WRAP" run "$MEM" --store mem.h5 --progress-interval 0 --max-deaths 4 >again.out 2>again.err
rc=$?
case $rc in 0 | 1 | 2 | 3) cat again.err >&2; fail "--max-deaths 4 exited $rc: the set-aside realizations were not handed out again" ;; esac
expect_in again.err "realizations in the sweep, 12 stored"
echo "ok: a worker killed for memory: $((runs - 1)) jobs died, the 4 realizations that killed them set aside with the reason, the 12 others identical"
