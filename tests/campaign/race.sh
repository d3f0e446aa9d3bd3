#!/bin/bash
# Issue 14, item 1: two `campaign run` started at once on a new store. Before the fix one run
# could delete the other's new journal before it was linked into place and then write every
# record into a deleted file, print "finished" and leave a journal with its header only. Made
# deterministic by pausing each run before it links its new journal (HOPPER_STORE_PAUSE): run A
# pauses 1.5 s; run B starts once A's private new journal exists (A is in its pause) and pauses
# 3 s, so A links first. Afterwards: one run did the work, the other was refused (or found
# everything stored), and the store holds every realization exactly once, identical to an
# uninterrupted run.
# The race is staged only if B creates its new journal before A links its own: the test checks
# that it did (B's private file seen while the store's journal did not exist yet), and if B's
# start took longer than A's pause (a loaded machine), tries again with pauses twice as long.
# A links first if it wakes from its pause less than its length late (B links its pause's length,
# twice A's, after its file appeared, which is after A's pause began): 1.5 s or more of
# scheduling delay for a sleeping process, beyond any load.
source "$(dirname "$0")/lib.sh"
reference
STORE=$WORK/race.h5
new_journal() {  # new_journal PID: the private new journal of that run exists
    compgen -G "$STORE.journal.new.$1.*" >/dev/null
}
alive() {  # alive PID: the background run still runs (not ended, nor a zombie)
    local st
    st=$(ps -o stat= -p "$1" 2>/dev/null)
    [ -n "$st" ] && [ "${st#Z}" = "$st" ]
}
staged=0
for pause in 1500 3000 6000; do
    rm -f "$STORE" "$STORE".*
    HOPPER_STORE_PAUSE=journal_link:$pause "$EXE" run "$MINI" --store "$STORE" \
        --progress-interval 0 >a.out 2>a.err &
    A=$!
    wait_until "run A creating its new journal" eval 'new_journal $A || ! alive $A'
    new_journal $A || { cat a.err >&2; fail "run A ended before it paused"; }
    HOPPER_STORE_PAUSE=journal_link:$((2 * pause)) "$EXE" run "$MINI" --store "$STORE" \
        --progress-interval 0 >b.out 2>b.err &
    B=$!
    # B's file first, then the store's journal: B's existed before A linked if A had not then.
    wait_until "run B creating its new journal or being refused" \
        eval 'new_journal $B || [ -e "$STORE.journal" ] || ! alive $B'
    new_journal $B && [ ! -e "$STORE.journal" ] && staged=1
    wait $A; rc_a=$?
    wait $B; rc_b=$?
    echo "pauses $pause and $((2 * pause)) ms: run A exited $rc_a, run B exited $rc_b; race staged: $staged"
    [ $staged -eq 1 ] && break
done
[ $staged -eq 1 ] || fail "run B never reached its new journal while run A was paused (pauses up to 6 s)"
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
