#!/bin/bash
# Issue 14, item 2: a store on a full disk. Before the fix the run printed "cannot flush ... No
# space left" and then crashed in HDF5's cleanup at exit (exit 139). Now it exits 1 saying that
# the journal holds what finished, and the same command on a disk with room resumes to results
# identical to an uninterrupted run.
# The full disk is a file size limit (ulimit -f, writes fail with EFBIG: the same failed write
# for HDF5 and the journal, and it needs no root); as root, also a real 200 kB tmpfs, without and
# with mpirun.
# Usage: full_disk.sh NP (0: the file size limit and the tmpfs in one process; NP > 0: the
# tmpfs under mpirun -np NP).
NP=${1:-0}
source "$(dirname "$0")/lib.sh"
reference

# check_full_run RC LOG: the run stopped with exit 1 and the message, no crash.
check_full_run() {
    [ "$1" -eq 1 ] || { cat "$2" >&2; fail "a run on a full disk exited $1, expected 1"; }
    expect_in "$2" "is safe in the journal"
}

# 1. A file size limit of 200 kB (the HDF5 file's fixed layout alone is about 300 kB).
if [ "$NP" -eq 0 ]; then
STORE=$WORK/limited.h5
(trap '' XFSZ; ulimit -f 200; exec "$EXE" run "$MINI" --store "$STORE" --progress-interval 0) \
    >limited.out 2>limited.err
check_full_run $? limited.err
run_expect 0 limited-resume "$EXE" run "$MINI" --store "$STORE" --progress-interval 0
digest "$STORE" limited.digest
same_digests "$WORK/ref.digest" limited.digest
fi

# 2. A real full file system (needs root for mount; skipped otherwise).
FS=$WORK/tmpfs
mkdir -p "$FS"
if [ "$(id -u)" -eq 0 ] && mount -t tmpfs -o size=200k tmpfs "$FS" 2>/dev/null; then
    trap 'umount "$FS" 2>/dev/null' EXIT
    how=threads
    [ "$NP" -gt 0 ] && how=mpi
    {
        rm -f "$FS"/*
        if [ "$how" = mpi ]; then
            mpirun -np "$NP" "$EXE" run "$MINI" --store "$FS/s.h5" --progress-interval 0 \
                >"$how.out" 2>"$how.err"
        else
            "$EXE" run "$MINI" --store "$FS/s.h5" --progress-interval 0 >"$how.out" 2>"$how.err"
        fi
        check_full_run $? "$how.err"
        # Resume exactly where there is room: move the store with its journal.
        mkdir -p "$WORK/$how" && cp "$FS/s.h5" "$FS/s.h5.journal" "$WORK/$how/"
        run_expect 0 "$how-resume" "$EXE" run "$MINI" --store "$WORK/$how/s.h5" --progress-interval 0
        digest "$WORK/$how/s.h5" "$how.digest"
        same_digests "$WORK/ref.digest" "$how.digest"
    }
    umount "$FS"
    trap - EXIT
else
    echo "note: not root or no tmpfs mount: the tmpfs case is skipped"
fi
echo "ok"
