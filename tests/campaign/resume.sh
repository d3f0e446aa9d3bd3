#!/bin/bash
# Resume rules: a sweep whose physics differs from the store's is refused naming what differs
# (a base parameter, the campaign seed); an extension (more realizations, a new point) runs only
# what is new and leaves every stored realization untouched; a second run at the same time is
# refused; status works while a run writes the store.
source "$(dirname "$0")/lib.sh"
reference
cp "$WORK/ref.h5" "$WORK/s.h5" && cp "$WORK/ref.h5.journal" "$WORK/s.h5.journal"

run_expect 2 physics "$EXE" run "$DATA/mini_physics.toml" --store "$WORK/s.h5"
expect_in physics.err "campaign: error: the sweep file's physics differs from the store's for 3 point(s) already in the store:"
expect_in physics.err "material.e_n = 0.6 (store: 0.5)"
expect_in physics.err "another --store path"
run_expect 2 seed "$EXE" run "$DATA/mini_seed.toml" --store "$WORK/s.h5"
expect_in seed.err "campaign seed 12 differs from the store's 11"

run_expect 0 extended "$EXE" run "$DATA/mini_extended.toml" --store "$WORK/s.h5" --progress-interval 0
expect_in extended.err "the sweep extends the campaign: 1 new point(s), 8 new realization(s)"
expect_in extended.err "20 realizations in the sweep, 12 stored"
digest "$WORK/s.h5" ext.digest
[ "$(wc -l <ext.digest)" -eq 20 ] || fail "extended store has $(wc -l <ext.digest) realizations"
comm -23 ref.digest ext.digest >missing.txt
[ ! -s missing.txt ] || { cat missing.txt >&2; fail "stored realizations changed or vanished"; }

# Status while a run writes; a second writer is refused.
rm -f "$WORK/live.h5"*
# The writer is frozen (lib.sh) once status sees it active with realizations still to run: it
# then holds the store for the status and the second run, however fast it is.
start_job "$EXE" run "$MINI" --store "$WORK/live.h5" --progress-interval 0
freeze_when "$WORK/live.h5" "s['active'] and s['pending'] > 0" "status seeing the run active"
run_expect 0 live "$EXE" status "$WORK/live.h5" --json
"$PY" -c 'import json,sys; s=json.load(open("live.out")); sys.exit(0 if s["active"] else 1)' ||
    fail "status does not see the run active"
run_expect 1 second "$EXE" run "$MINI" --store "$WORK/live.h5"
expect_in second.err "is in use by another \`campaign run\`"
thaw_job
wait "$JOB" || { cat job.err >&2; fail "the run failed while status read it"; }
digest "$WORK/live.h5" live.digest
same_digests ref.digest live.digest
echo "ok"
