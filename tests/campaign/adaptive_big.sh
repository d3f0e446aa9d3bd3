#!/bin/bash
# Issue 29, item 2: a campaign with a target costs memory and disk in proportion to what has run
# and what its current round plans, not to max_realizations. data/mini_adaptive.toml on two
# points with a target it never meets (target_rel_ci = 0.01) and max_realizations = 1000000
# (before the fix: 2 000 000 tasks in the dry run, 1.1 GB of memory and a 16 MB journal plus a
# 21 MB HDF5 file after 50 realizations) against the same campaign with max_realizations = 4:
# the dry run lists the first round, the run stays small in memory and on disk, and it runs the
# same realizations with the same seeds, bit for bit. With the argument "old", a store written
# before the fix (data/store_before_issue29.tar.gz, below) resumes to the same realizations
# (those it computes bit for bit; its 3 stored ones came from 0.3.0's arithmetic).
source "$(dirname "$0")/lib.sh"
edit() {  # edit OUT MAX: mini_adaptive.toml on D = 1.6, 1.9 cm, a target never met, MAX
    sed -e 's/^target_rel_ci = 0.5$/target_rel_ci = 0.01/' \
        -e "s/^max_realizations = 4\$/max_realizations = $2/" \
        -e 's/^D_cm = \[1.6, 1.9, 3.5\]$/D_cm = [1.6, 1.9]/' "$DATA/mini_adaptive.toml" >"$1"
    grep -q "^max_realizations = $2\$" "$1" && grep -q '^D_cm = \[1.6, 1.9\]$' "$1" ||
        fail "mini_adaptive.toml changed: cannot make $1"
}
edit big.toml 1000000
edit small.toml 4

if [ "${1:-}" = old ]; then
    # data/store_before_issue29.tar.gz: the journal of small.toml run by commit 5cef94a (its
    # plan lists every seed, no limit; no allotment records), stopped after 3 realizations.
    tar xzf "$DATA/store_before_issue29.tar.gz" -C "$WORK" || fail "cannot unpack the fixture"
    [ -e old.h5.journal ] && [ ! -e old.h5 ] || fail "the fixture is a journal alone"
    run_expect 0 old_status "$EXE" status old.h5 --json
    expect_in old_status.out '"done": 3'
    # The dry run plans what the run will do (the current round's missing realizations, as
    # status says), not every seed the old journal lists (it said 5 where 1 runs).
    pending=$("$PY" -c 'import json,sys; print(json.load(open(sys.argv[1]))["pending"])' old_status.out)
    run_expect 0 old_dry "$EXE" run small.toml --store old.h5 --dry-run
    total=$(awk '$1 == "total" {print $2}' old_dry.out)
    [ -n "$pending" ] && [ "$total" = "$pending" ] ||
        { cat old_dry.out >&2; fail "the dry run plans ${total:-?}, status says ${pending:-?} pending"; }
    run_expect 0 small "$EXE" run small.toml --store small.h5 --progress-interval 0
    run_expect 0 old "$EXE" run small.toml --store old.h5 --progress-interval 0
    digest small.h5 small.digest
    digest old.h5 old.digest
    # The same realizations (points, indices, seeds) as the fresh run. The fixture's 3 were
    # computed by 0.3.0's engine arithmetic and stay as stored; the 5 this build adds equal the
    # fresh run's bit for bit (0.4.0 changed the arithmetic: CHANGELOG).
    cmp -s <(cut -f1-3 small.digest) <(cut -f1-3 old.digest) ||
        { diff small.digest old.digest >&2; fail "the resumed store holds other realizations or seeds"; }
    ndiff=$(diff small.digest old.digest | grep -c '^>' || true)
    [ "$ndiff" -le 3 ] || { diff small.digest old.digest >&2; fail "$ndiff realizations differ from the fresh run; only the fixture's 3 may"; }
    [ "$(wc -l <old.digest)" -eq 8 ] || fail "$(wc -l <old.digest) realizations, expected 8"
    echo "ok: a store written before the fix resumes to the same 8 realizations"
    exit 0
fi

# 1. The dry run: the first round (2 per point), not max_realizations.
run_expect 0 dry "$EXE" run big.toml --store big.h5 --dry-run
grep -Eq '^total +4 ' dry.out || { cat dry.out >&2; fail "the dry run does not plan the first round"; }
expect_in dry.out "up to max_realizations = 1000000"
[ ! -e big.h5.journal ] || fail "the dry run wrote a journal"

# 2. The small campaign to its end: rounds of 2 up to 4 per point, 8 realizations.
run_expect 0 small "$EXE" run small.toml --store small.h5 --progress-interval 0
expect_in small.err "max_realizations = 4 reached"
digest small.h5 small.digest
[ "$(wc -l <small.digest)" -eq 8 ] || fail "$(wc -l <small.digest) realizations, expected 8"

# 3. The large one, stopped by SIGTERM once it holds 12 realizations (three rounds).
start_job "$EXE" run big.toml --store big.h5 --progress-interval 0
wait_stored big.h5 12  # no race: a target it never meets, the run would go on for ever
hwm=$(awk '/^VmHWM/ {print $2}' "/proc/$JOB/status")
kill_job TERM
[ "$JOB_RC" -eq 4 ] || { cat job.err >&2; fail "the stopped run exited $JOB_RC, expected 4"; }
# Memory: about 30 MB (1.1 GB before the fix).
[ -n "$hwm" ] && [ "$hwm" -lt 150000 ] || fail "peak memory ${hwm:-?} kB (at most 150 MB expected)"
# Disk: a few kB per realization and the plan of the rounds (37 MB before the fix).
journal=$(stat -c %s big.h5.journal)
file=$(stat -c %s big.h5)
[ "$journal" -lt 1000000 ] || fail "journal of $journal bytes after a few realizations"
[ "$file" -lt 2000000 ] || fail "HDF5 file of $file bytes after a few realizations"
# The HDF5 view lists the allotted realizations only.
"$PY" - big.h5 <<'PYEOF' || fail "the HDF5 view lists more than the rounds allotted"
import sys, h5py
f = h5py.File(sys.argv[1], "r")
tasks, planned = len(f["tasks/seed"]), [int(x) for x in f["points/realizations"][:]]
# 6 per point after three rounds (8 once the fourth is allotted), far below the limit.
assert tasks == sum(planned) and all(6 <= n <= 40 for n in planned), (tasks, planned)
PYEOF

# 4. The same realizations, seeds and physics as max_realizations = 4 where both ran.
digest big.h5 big.digest
awk -F'\t' '$2 < 4' big.digest >big4.digest
same_digests small.digest big4.digest

# 5. status and a resumed dry run tell the rounds so far and the limit.
run_expect 0 status "$EXE" status big.h5
expect_in status.out "up to"
grep -Eq '^D_cm=1.6 theta_deg=60 +[0-9]+ +[0-9]+ +0 +[0-9]+ +1000000$' status.out ||
    { cat status.out >&2; fail "status does not show the point's limit"; }
run_expect 0 status_json "$EXE" status big.h5 --json
expect_in status_json.out '"limit": 1000000'
run_expect 0 dry2 "$EXE" run big.toml --store big.h5 --dry-run
total=$(awk '$1 == "total" {print $2}' dry2.out)
[ -n "$total" ] && [ "$total" -le 8 ] || { cat dry2.out >&2; fail "the dry run on the store plans $total"; }
echo "ok: max_realizations = 1000000 after $(wc -l <big.digest) realizations: ${hwm} kB peak," \
    "journal $journal bytes, HDF5 $file bytes; the same realizations as max_realizations = 4"
