#!/bin/bash
# Build item 4 of issue 14: file systems without locks (NFS without a lock daemon, Lustre mounted
# without flock), simulated by an LD_PRELOAD shim ($NOLOCKS) that fails every lock call.
#   - without a switch, `campaign run` refuses (exit 1) before writing anything, naming the
#     problem and --no-file-locking (before, it went on without the journal's lock, and HDF5
#     failed with "unable to lock file");
#   - with --no-file-locking it runs, says that nothing prevents two runs, and the results equal
#     an uninterrupted run; status works; analyze needs HDF5_USE_FILE_LOCKING=FALSE and says so;
#   - HDF5_USE_FILE_LOCKING=FALSE on a file system with locks: runs, and the journal's lock
#     still refuses a second run.
source "$(dirname "$0")/lib.sh"
reference
run_nolocks() { LD_PRELOAD=$NOLOCKS "$@"; }

for flock_errno in ENOLCK ENOSYS; do
    export HOPPER_NO_LOCKS_FLOCK=$flock_errno
    mkdir -p "$WORK/$flock_errno"
    STORE=$WORK/$flock_errno/s.h5
    run_expect 1 refused-$flock_errno run_nolocks "$EXE" run "$MINI" --store "$STORE" --progress-interval 0
    expect_in refused-$flock_errno.err "cannot lock the store's journal"
    expect_in refused-$flock_errno.err "--no-file-locking"
    [ -z "$(ls -A "$WORK/$flock_errno")" ] || fail "files left after the refusal: $(ls "$WORK/$flock_errno")"

    run_expect 0 unlocked-$flock_errno run_nolocks "$EXE" run "$MINI" --store "$STORE" \
        --progress-interval 0 --no-file-locking
    expect_in unlocked-$flock_errno.err "does not support locks (--no-file-locking): nothing prevents two runs"
    digest "$STORE" $flock_errno.digest
    same_digests ref.digest $flock_errno.digest
    run_expect 0 status-$flock_errno run_nolocks "$EXE" status "$STORE" --json
    expect_in status-$flock_errno.out '"done": 12'
done

# HDF5's locks fail with ENOLCK (NFS): analyze says what to do, and does it with the switch.
export HOPPER_NO_LOCKS_FLOCK=ENOLCK
run_expect 1 analyze-locked run_nolocks "$EXE" analyze "$WORK/ENOLCK/s.h5"
expect_in analyze-locked.err "HDF5_USE_FILE_LOCKING=FALSE"
HDF5_USE_FILE_LOCKING=FALSE run_expect 0 analyze-unlocked run_nolocks "$EXE" analyze "$WORK/ENOLCK/s.h5"
expect_in analyze-unlocked.out "analysis written to"

# HDF5_USE_FILE_LOCKING=FALSE where locks work: the journal's lock still keeps one writer.
export HDF5_USE_FILE_LOCKING=FALSE
STORE=$WORK/hdf5-unlocked.h5
start_job "$EXE" run "$MINI" --store "$STORE" --progress-interval 0
wait_stored "$STORE" 1
run_expect 1 second "$EXE" run "$MINI" --store "$STORE" --progress-interval 0
expect_in second.err "is in use by another \`campaign run\`"
wait "$JOB" || { cat job.err >&2; fail "the first run failed"; }
digest "$STORE" hdf5-unlocked.digest
same_digests ref.digest hdf5-unlocked.digest
echo "ok"
