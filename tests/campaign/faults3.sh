#!/bin/bash
# Issue 29 ("Faults, round 3"), end to end with the campaign executable:
#  1. a checkpoint whose CRC-32C is right but whose state is not (the neighbour list's row start
#     of one particle set to -1000000, checksum recomputed): refused with the reason, the
#     realization restarts, the rerun exits 0 and every realization equals an uninterrupted
#     run's (before: SIGSEGV at every resume, nothing ever stored);
#  3. deadlines: absurd numbers, dates that do not exist and ones after 9999 refused (exit 2, the
#     deadline's message, no store); 9999-12-31T23:59:59Z and UTC offsets taken;
#  4. a deadline already past starts nothing and says so (exit 2, no store);
#  5. a full disk at the end (the analysis not written): exit 5, and status does not call the
#     store complete; the store moved where there is room resumes to exit 0, results identical;
#  6. a steady state whose outlet is so wide that it never jams (D = 9 cm in a 10 cm hopper):
#     re-insertion finds room and the realization ends at max_time_s as time_limit (before:
#     failed, exit 3);
#  7. 10 million disks in a 10 cm hopper: refused before anything is built (exit 2);
#  8. simulate --point on a realization not stored yet: exit 2 with the reason; a string or a
#     boolean for target_rel_ci: the wrong type, naming the key and the type expected.
source "$(dirname "$0")/lib.sh"
SWEEP=$DATA/ckpt.toml

# --- 1. A checkpoint with a valid checksum over a broken state -----------------------------------
run_expect 0 ref "$EXE" run "$SWEEP" --store "$WORK/ref.h5" --progress-interval 0 --threads 2
digest "$WORK/ref.h5" ref.digest
STORE=$WORK/c.h5
: >job.err
start_job "$EXE" run "$SWEEP" --store "$STORE" --progress-interval 0 --threads 2
# SIGTERM with the run frozen (lib.sh) while a realization has run for 0.4 s: it is still
# running when the signal comes (its state is saved), however fast the machine.
freeze_when "$STORE" "s['running'] and max(t['seconds'] for t in s['running']) >= 0.4" \
    "a realization running for 0.4 s"
kill -TERM "$JOB"
thaw_job
wait "$JOB"
[ $? -eq 4 ] || { cat job.err >&2; fail "SIGTERM: expected exit 4"; }
victim=$(ls "$STORE.checkpoints"/*.ckpt | head -1)
[ -n "$victim" ] || fail "no checkpoint after SIGTERM"
"$PY" - "$victim" <<'PY' || fail "breaking the checkpoint's state"
import os, struct, sys
sys.path.insert(0, os.path.join(os.environ["SRC"], "tests", "campaign"))
from ckpt_file import read_body, write_body
body = bytearray(read_body(sys.argv[1]))
u64 = lambda o: struct.unpack_from("<Q", body, o)[0]
i32 = lambda o: struct.unpack_from("<i", body, o)[0]
# The neighbour list: row starts (n + 1 ints from 0, non-decreasing), the partner list (as long
# as the last row start), then the wall row starts (n + 1 ints again).
found = None
for o in range(0, len(body) - 16):
    c = u64(o)
    if c < 10 or c > 100000 or o + 8 + 4 * c + 8 > len(body) or i32(o + 8) != 0:
        continue
    starts = struct.unpack_from("<%di" % c, body, o + 8)
    if any(starts[k] > starts[k + 1] for k in range(c - 1)) or starts[-1] <= 0:
        continue
    pj = o + 8 + 4 * c
    if u64(pj) != starts[-1] or pj + 8 + 4 * starts[-1] + 8 > len(body):
        continue
    if u64(pj + 8 + 4 * starts[-1]) != c:
        continue
    found = o + 8
    break
assert found is not None, "no neighbour list found in the checkpoint"
struct.pack_into("<i", body, found + 4 * 3, -1000000)
write_body(sys.argv[1], body)
PY
run_expect 0 rerun "$EXE" run "$SWEEP" --store "$STORE" --progress-interval 0 --threads 2
expect_in rerun.err "the checkpoint's state is inconsistent (a neighbour list row start"
expect_in rerun.err "is removed and the realization starts again from its beginning"
[ ! -e "$STORE.checkpoints" ] || fail "checkpoints left: $(ls "$STORE.checkpoints")"
digest "$STORE" c.digest
same_digests ref.digest c.digest

# --- 8. simulate --point on a realization not stored; wrong TOML types ----------------------------
label=$("$PY" -c "
import json, subprocess, sys
s = json.loads(subprocess.run(['$EXE', 'status', '$WORK/ref.h5', '--json'], capture_output=True).stdout)
print(s['points'][0]['label'])")
sed 's/^realizations = 2$/realizations = 3/' "$SWEEP" >three.toml
grep -q '^realizations = 3$' three.toml || fail "three.toml"
mkdir -p "$WORK/ref3" && cp "$WORK/ref.h5" "$WORK/ref.h5.journal" "$WORK/ref3/"
# The plan grows to 3 realizations a point, the third not stored: the test hook kills the run
# at its second journal append (the run-start record is the first).
HOPPER_STORE_CRASH=journal:2 "$EXE" run three.toml --store "$WORK/ref3/ref.h5" \
    --progress-interval 0 >crash.out 2>crash.err
run_expect 2 notstored "$EXE" simulate --store "$WORK/ref3/ref.h5" --point "$label" --realization 2
expect_in notstored.err "is not stored yet"
run_expect 0 stored "$EXE" simulate --store "$WORK/ref.h5" --point "$label" --realization 1
expect_in stored.err "identical to the stored realization"
for v in '"0.1"' 'true'; do
    sed "s/^target_rel_ci = 0.5$/target_rel_ci = $v/" "$DATA/mini_adaptive.toml" >type.toml
    grep -q "^target_rel_ci = $v$" type.toml || fail "type.toml"
    run_expect 2 type "$EXE" run type.toml --store "$WORK/type.h5" --dry-run
    expect_in type.err "campaign.target_rel_ci = $v has the wrong type: expected a number"
done

# --- 3 and 4. Deadlines -----------------------------------------------------------------------
d400=$(printf '9%.0s' $(seq 1 400))
for bad in "@$d400" "+$d400" "+${d400}h" "+99999999999999999999h" "2026-02-31T00:00:00Z" \
    "2026-11-26T10:00:00+24:00" "10000-01-01T00:00:00Z" "@253402300800"; do
    run_expect 2 badd env -u SLURM_JOB_ID "$EXE" run "$MINI" --store "$WORK/x.h5" --deadline "$bad"
    expect_in badd.err "--deadline '$bad'"
    ! grep -q "stod\|out_of_range" badd.err || fail "a raw exception for --deadline $bad"
done
for past in +0 @1 2000-01-01T00:00:00Z 2026-01-01T05:30:00+05:30; do
    run_expect 2 past env -u SLURM_JOB_ID "$EXE" run "$MINI" --store "$WORK/x.h5" --deadline "$past"
    expect_in past.err "the deadline has already passed"
done
[ ! -e "$WORK/x.h5" ] && [ ! -e "$WORK/x.h5.journal" ] || fail "a refused deadline created a store"
run_expect 0 far env -u SLURM_JOB_ID "$EXE" run "$MINI" --store "$WORK/far.h5" \
    --progress-interval 0 --deadline 9999-12-31T23:59:59Z
run_expect 0 offset env -u SLURM_JOB_ID "$EXE" run "$MINI" --store "$WORK/far.h5" \
    --progress-interval 0 --deadline 9998-01-01T05:30:00+05:30
digest "$WORK/far.h5" far.digest
run_expect 0 miniref "$EXE" run "$MINI" --store "$WORK/mini.h5" --progress-interval 0
digest "$WORK/mini.h5" mini.digest
same_digests mini.digest far.digest

# --- 5. The analysis not written (a full disk at the end) ----------------------------------------
FS=$WORK/tmpfs
mkdir -p "$FS"
if [ "$(id -u)" -eq 0 ] && mount -t tmpfs -o size=520k tmpfs "$FS" 2>/dev/null; then
    trap 'umount "$FS" 2>/dev/null' EXIT
    "$EXE" run "$MINI" --store "$FS/s.h5" --progress-interval 0 >full.out 2>full.err
    rc=$?
    if grep -q "analysis not written into the store" full.err; then
        [ "$rc" -eq 5 ] || { cat full.err >&2; fail "analysis not written: exit $rc, expected 5"; }
        expect_in full.err "every realization is stored"
        run_expect 0 fullst "$EXE" status "$FS/s.h5" --json
        "$PY" -c "
import json
s = json.load(open('fullst.out'))
assert s['done'] == 12 and not s['hdf5_in_step'], s" || fail "status called the store complete"
        mkdir -p "$WORK/moved" && cp "$FS/s.h5" "$FS/s.h5.journal" "$WORK/moved/"
        run_expect 0 moved "$EXE" run "$MINI" --store "$WORK/moved/s.h5" --progress-interval 0
        expect_in moved.out "analysis written to"
        digest "$WORK/moved/s.h5" moved.digest
        same_digests mini.digest moved.digest
    else
        # The window between "the realizations fit" and "the analysis fits too" moved: say so.
        cat full.err >&2
        fail "a 520 kB tmpfs did not fill up at the analysis (exit $rc); adjust the size"
    fi
    umount "$FS"
    trap - EXIT
else
    echo "note: not root or no tmpfs mount: case 5 is skipped"
fi

# --- 6. A steady state with an outlet too wide to jam ---------------------------------------------
cat >steady.toml <<'EOF'
[hopper]
width_cm = 10.0
particles = 300
theta_deg = 60.0

[material]
collision_time_s = 8.0e-4

[integrator]
scheme = "gear4"
steps_per_collision = 50
contact_corrections = false

[protocol]
mode = "steady_state"
jams_per_realization = 5
max_time_s = 1.0

[campaign]
name = "steady"
seed = 3
realizations = 1

[sweep]
D_cm = [9.0]
EOF
run_expect 0 steady "$EXE" run steady.toml --store "$WORK/steady.h5" --progress-interval 0
expect_in steady.out "0/0/0/1"  # complete/failed/arrested/time_limit

# --- 7. A scene that cannot hold its particles ----------------------------------------------------
sed -e 's/^particles = 300$/particles = 10000000/' -e 's/^mode = "steady_state"$/mode = "published"/' \
    -e '/^jams_per_realization/d' steady.toml >huge.toml
grep -q '^particles = 10000000$' huge.toml || fail "huge.toml"
t0=$(date +%s.%N)
run_expect 2 huge "$EXE" run huge.toml --store "$WORK/huge.h5" --progress-interval 0
took=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }')
expect_in huge.err "does not fit a hopper 0.1 m wide"
# Margin: the refusal takes about 0.02 s (startup included); building the scene took gigabytes
# and was still going after 31 s (a46ae6e). 5 s is 250 times the refusal, far beyond load.
awk -v t="$took" 'BEGIN { exit !(t < 5) }' || fail "the refusal took $took s"
[ ! -e "$WORK/huge.h5" ] || fail "a refused scene created a store"
echo "faults3.sh: passed (refusal of 10 million disks in $took s)"
