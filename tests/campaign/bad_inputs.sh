#!/bin/bash
# Bad sweep files (wrong types, unknown keys, empty lists, D wider than the hopper, no
# [campaign]) exit 2 with the file, key and problem named; damaged or foreign stores exit 1 with
# a clear message and are left untouched.
source "$(dirname "$0")/lib.sh"
cp "$MINI" mini.toml
bad() {  # bad NAME EXPECTED-TEXT < sweep text
    cat >"$1.toml"
    run_expect 2 "$1" "$EXE" run "$1.toml" --store "$WORK/$1.h5"
    expect_in "$1.err" "campaign: error: "
    expect_in "$1.err" "$2"
    [ ! -e "$WORK/$1.h5.journal" ] || fail "$1: a store was created for a bad sweep file"
}
sed 's/^particles = 100/particles = "many"/' mini.toml | bad wrong_type "hopper.particles"
sed 's/^seed = 11/seed = 11\nsede = 3/' mini.toml | bad unknown_key "sede"
sed 's/^D_cm = \[1.9, 2.6, 3.5\]/D_cm = []/' mini.toml | bad empty_list "D_cm"
sed 's/^D_cm = \[1.9, 2.6, 3.5\]/D_cm = [1.9, 9.0]/' mini.toml | bad wide_outlet "width_cm"
sed '/^\[campaign\]/,$d' mini.toml | bad no_campaign "no [campaign] section"
run_expect 2 missing "$EXE" run "$WORK/nothing.toml"
run_expect 2 usage "$EXE" run
expect_in usage.err "missing the sweep file"
run_expect 2 bad_grace "$EXE" run mini.toml --grace -1
expect_in bad_grace.err "--grace must be >= 0"
# The test hooks' variables (tests only) name what they accept too.
HOPPER_STORE_STOP=results:2 run_expect 2 bad_stop "$EXE" run mini.toml --store "$WORK/stop.h5"
expect_in bad_stop.err "HOPPER_STORE_STOP must be result:<n>, got 'results:2'"
HOPPER_STORE_STOP=result:0 run_expect 2 zero_stop "$EXE" run mini.toml --store "$WORK/stop.h5"
expect_in zero_stop.err "HOPPER_STORE_STOP's n must be 1 to 1000000, got 'result:0'"

# A foreign file where the store should be.
echo "not a store" >foreign.h5
run_expect 1 foreign "$EXE" run mini.toml --store "$WORK/foreign.h5"
expect_in foreign.err "exists and is not a hopper store (not an HDF5 file)"
expect_in foreign.h5 "not a store"
"$PY" -c 'import h5py; f = h5py.File("other.h5", "w"); f["x"] = [1, 2, 3]' || fail "h5py"
run_expect 1 foreign_h5 "$EXE" run mini.toml --store "$WORK/other.h5"
expect_in foreign_h5.err "not a hopper store"
run_expect 1 status_foreign "$EXE" status "$WORK/other.h5"
expect_in status_foreign.err "is not a hopper store"
run_expect 1 status_missing "$EXE" status "$WORK/none.h5"
expect_in status_missing.err "no store at"

# A damaged journal (a byte changed in the middle, not a torn tail) is refused, not truncated.
run_expect 0 good "$EXE" run mini.toml --store "$WORK/good.h5" --progress-interval 0
size=$(stat -c %s good.h5.journal)
"$PY" -c 'import sys
f = open("good.h5.journal", "r+b"); n = int(sys.argv[1]) // 2
f.seek(n); b = f.read(1); f.seek(n); f.write(bytes([b[0] ^ 0xFF]))' "$size"
run_expect 1 damaged "$EXE" run mini.toml --store "$WORK/good.h5"
expect_in damaged.err "is damaged: an invalid record at byte"
[ "$(stat -c %s good.h5.journal)" -eq "$size" ] || fail "a damaged journal was truncated"
run_expect 1 damaged_status "$EXE" status "$WORK/good.h5"
expect_in damaged_status.err "is damaged"
# A journal that is not one.
echo "garbage garbage garbage" >g.h5.journal
run_expect 1 garbage "$EXE" run mini.toml --store "$WORK/g.h5"
expect_in garbage.err "is not a hopper journal"
echo "ok"
