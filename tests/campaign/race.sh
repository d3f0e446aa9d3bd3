#!/bin/bash
# Issue 14, item 1: two `campaign run` started at once on a new store. Before the fix one run
# could delete the other's new journal before it was linked into place and then write every
# record into a deleted file, print "finished" and leave a journal with its header only. Made
# deterministic by pausing each run before it links its new journal (HOPPER_STORE_PAUSE): run A
# pauses 1.5 s, run B starts 0.5 s later (while A is paused) and pauses 3 s, so A links first.
# Afterwards: one run did the work, the other was refused (or found everything stored), and the
# store holds every realization exactly once, identical to an uninterrupted run.
source "$(dirname "$0")/lib.sh"
reference
STORE=$WORK/race.h5
HOPPER_STORE_PAUSE=journal_link:1500 "$EXE" run "$MINI" --store "$STORE" --progress-interval 0 \
    >a.out 2>a.err &
A=$!
sleep 0.5
HOPPER_STORE_PAUSE=journal_link:3000 "$EXE" run "$MINI" --store "$STORE" --progress-interval 0 \
    >b.out 2>b.err &
B=$!
wait $A; rc_a=$?
wait $B; rc_b=$?
echo "run A exited $rc_a, run B exited $rc_b"
[ $rc_a -eq 0 ] || { cat a.err >&2; fail "run A exited $rc_a"; }
if [ $rc_b -eq 1 ]; then
    expect_in b.err "is in use by another \`campaign run\`"
elif [ $rc_b -ne 0 ]; then
    cat b.err >&2; fail "run B exited $rc_b"
fi
"$EXE" status "$STORE" --json >status.json || fail "status"
"$PY" - status.json <<'PY' || fail "status after the race"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["done"] == 12 and s["pending"] == 0, s
PY
digest "$STORE" race.digest
same_digests "$WORK/ref.digest" race.digest
leftover=$(ls "$WORK" | grep -c '\.journal\.new' || true)
[ "$leftover" -eq 0 ] || fail "temporary journal files left behind: $(ls "$WORK")"
# A third run later resumes (nothing to run) instead of overwriting anything.
run_expect 0 third "$EXE" run "$MINI" --store "$STORE" --progress-interval 0
digest "$STORE" third.digest
same_digests "$WORK/ref.digest" third.digest
echo "ok"
