#!/bin/bash
# `campaign submit --dry-run`: every option given shows in the rendered batch script, optional
# #SBATCH lines are left out, nothing is written; bad values are refused with exit 2 and a
# message naming the option; without sbatch on PATH a real submit fails clearly (exit 1).
set -u
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK" || exit 1
TINY=$SRC/tests/slurm/data/tiny.toml
fail() {
    echo "FAIL: $*" >&2
    exit 1
}
expect_in() { grep -qF -- "$2" "$1" || { cat "$1" >&2; fail "'$1' lacks: $2"; }; }

"$EXE" submit "$TINY" --store "$WORK/sub/c.h5" --nodes 3 --ntasks 17 --time 2-03:04:05 \
    --partition compute --account proj_42 --max-resubmits 7 --signal-lead 300 --grace 100 \
    --launcher mpirun --job-name myjob --dry-run >full.sh 2>full.err || { cat full.err; fail "dry run"; }
for want in "#SBATCH --job-name=myjob" "#SBATCH --nodes=3" "#SBATCH --ntasks=17" \
    "#SBATCH --time=2-03:04:05" "#SBATCH --partition=compute" "#SBATCH --account=proj_42" \
    "#SBATCH --signal=B:USR1@300" "#SBATCH --output=$WORK/sub/c.h5.slurm.log" \
    "#SBATCH --open-mode=append" "max_resubmits=7" "grace=100" "launcher=mpirun" \
    "store='$WORK/sub/c.h5'" "sweep='$TINY'" "script='$WORK/sub/c.h5.sbatch'" "campaign='$EXE'"; do
    expect_in full.sh "$want"
done
head -n 1 full.sh | grep -qx '#!/bin/bash' || fail "no #!/bin/bash first line"
grep -q '{{' full.sh && fail "a placeholder is left: $(grep '{{' full.sh)"
bash -n full.sh || fail "the rendered script is not valid bash"
[ -e "$WORK/sub" ] && fail "--dry-run wrote something"

# Defaults; no partition or account lines without the options.
"$EXE" submit "$TINY" --store "$WORK/d.h5" --dry-run >default.sh || fail "default dry run"
for want in "#SBATCH --job-name=hopper-tiny" "#SBATCH --nodes=1" "#SBATCH --ntasks=2" \
    "#SBATCH --time=1:00:00" "#SBATCH --signal=B:USR1@120" "max_resubmits=10" "grace=60" \
    "launcher=srun"; do
    expect_in default.sh "$want"
done
grep -qE "^#SBATCH --(partition|account)" default.sh && fail "empty partition/account line kept"
echo ". /dev/null" >setup.sh
"$EXE" submit "$TINY" --store "$WORK/d.h5" --setup setup.sh --dry-run >setup.out || fail "--setup"
expect_in setup.out "source '$WORK/setup.sh'"

# Bad values: exit 2 and a message naming the option.
bad() {
    local want=$1
    shift
    "$EXE" submit "$TINY" --store "$WORK/b.h5" --dry-run "$@" >bad.out 2>bad.err
    local rc=$?
    [ "$rc" -eq 2 ] || fail "'$*' exited $rc, expected 2"
    expect_in bad.err "$want"
}
bad "--time must be a Slurm time" --time 1:2:3:4
bad "--time must be a Slurm time" --time 1h
bad "--time must be longer than zero" --time 0
bad "--nodes must be between 1" --nodes 0
bad "--ntasks must be a non-negative integer" --ntasks -3
bad "--ntasks (2) must be at least --nodes (4)" --nodes 4
bad "--partition must be 1-64 letters" --partition "a b"
bad "--account must be 1-64 letters" --account 'x;rm'
bad "--signal-lead (120 s) must be shorter than --time" --time 2
bad "--grace (200 s) must be shorter than --signal-lead" --grace 200
bad "--launcher must be srun, mpirun or none" --launcher aprun
bad "--setup file" --setup /nonexistent/env.sh
bad "--max-resubmits must be a non-negative integer" --max-resubmits x
bad "unrecognised option '--nodez'" --nodez 2
"$EXE" submit --dry-run >none.out 2>none.err
[ $? -eq 2 ] && expect_in none.err "missing the sweep file"

# No sbatch: a clear error, nothing submitted.
PATH=/nonexistent "$EXE" submit "$TINY" --store "$WORK/n.h5" >nosb.out 2>nosb.err
rc=$?
[ "$rc" -eq 1 ] || fail "without sbatch: exit $rc, expected 1"
expect_in nosb.err "sbatch not found on PATH"

"$EXE" help submit >help.out || fail "help submit"
expect_in help.out "usage: campaign submit SWEEP.toml"
"$EXE" --help | grep -q "^  submit " || fail "campaign --help does not list submit"
echo "ok"
