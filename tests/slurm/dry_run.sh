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
bad "--mem must be a number with an optional unit" --mem 4GB
bad "--qos must be 1-64 letters" --qos "a;b"
bad "--constraint must be node features" --constraint "a b"
bad "--mail-type must be a comma-separated list of NONE, BEGIN" --mail-type SOMETIMES
bad "--mail-user must be a user name or e-mail address" --mail-user "a b@c"
bad "--cpus-per-task must be between 1 and 4096" --cpus-per-task 0
bad "--sbatch-arg must be an sbatch option starting with '-'" --sbatch-arg gres=gpu:1
bad "would override what the template needs (--signal)" --sbatch-arg=--signal=B:USR2@60
bad "would override what the template needs (-o)" --sbatch-arg=-oother.log
bad "--launcher-arg must be one non-empty argument without quotes" "--launcher-arg=a'b"
bad "--master-slot must be shared or own" --master-slot half
bad "--deadline must be slurm or none for submit" --deadline +5m
bad "--checkpoint-interval and --no-checkpoints contradict" --no-checkpoints --checkpoint-interval 9
bad "--threads must be between 1 and 4096" --threads 0

# Site options (issue 15): each shows as its #SBATCH line or on the launcher's / run's command
# line; ignored ones are warned about; stderr has the cost estimate of the dry run.
"$EXE" submit "$TINY" --store "$WORK/o.h5" --dry-run --cpus-per-task 2 --mem 4G --qos high \
    --constraint 'haswell&ib' --mail-type END,FAIL --mail-user me@example.org --exclusive \
    --sbatch-arg=--gres=gpu:0 --sbatch-arg=--reservation=r1 --launcher-arg=--cpu-bind=cores \
    --launcher-arg=--mpi=pmix_v4 --checkpoint-interval 300 --threads 1 >opts.sh 2>opts.err ||
    { cat opts.err; fail "dry run with site options"; }
for want in "#SBATCH --cpus-per-task=2" "#SBATCH --mem=4G" "#SBATCH --qos=high" \
    "#SBATCH --constraint=haswell&ib" "#SBATCH --mail-type=END,FAIL" \
    "#SBATCH --mail-user=me@example.org" "#SBATCH --exclusive" "#SBATCH --gres=gpu:0" \
    "#SBATCH --reservation=r1" "launcher_args=('--cpu-bind=cores' '--mpi=pmix_v4')" \
    "run_args=(--checkpoint-interval 300 --deadline slurm-60)" "master_slot=shared"; do
    expect_in opts.sh "$want"
done
bash -n opts.sh || fail "the script with site options is not valid bash"
expect_in opts.err "warning: --cpus-per-task 2 with 1 thread(s) per rank: 1 of every 2 CPUs stay idle"
expect_in opts.err "dry run: $TINY on $WORK/o.h5 (new)"
expect_in opts.err "to run"
grep -Eq "^total +405 +[0-9.]+$" opts.err || { cat opts.err; fail "no total core-hours"; }
expect_in opts.err "on 2 workers"   # --ntasks 2 with the master beside them
[ -e "$WORK/o.h5" ] && fail "submit --dry-run created the store"
for o in "#SBATCH --cpus-per-task" "#SBATCH --mem" "#SBATCH --qos" "#SBATCH --exclusive" \
    "#SBATCH --mail"; do
    grep -qF -- "$o" default.sh && fail "default script has '$o'"
done
expect_in default.sh "run_args=(--deadline slurm-60)"
"$EXE" submit "$TINY" --store "$WORK/n1.h5" --dry-run --launcher none --ntasks 3 \
    --launcher-arg=-x --master-slot own >none1.sh 2>none1.err || fail "launcher none"
expect_in none1.sh "run_args=(--threads 3 --deadline slurm-60)"
expect_in none1.err "warning: --launcher-arg is ignored with --launcher none"
expect_in none1.err "warning: --master-slot is ignored with --launcher none"
"$EXE" submit "$TINY" --store "$WORK/n2.h5" --dry-run --master-slot own --ntasks 4 \
    --no-checkpoints --deadline none >own.sh 2>own.err || fail "master-slot own"
expect_in own.sh "master_slot=own"
expect_in own.sh "run_args=(--no-checkpoints --deadline none)"
expect_in own.err "on 3 workers"
# Hybrid: --cpus-per-task 4 gives each rank 4 worker threads; --threads beyond it is warned.
"$EXE" submit "$TINY" --store "$WORK/h.h5" --dry-run --ntasks 2 --cpus-per-task 4 >hy.sh 2>hy.err ||
    fail "hybrid dry run"
expect_in hy.sh "run_args=(--threads 4 --deadline slurm-60)"
expect_in hy.err "on 8 workers"
grep -q warning hy.err && fail "hybrid with matching --cpus-per-task warned: $(cat hy.err)"
"$EXE" submit "$TINY" --store "$WORK/h.h5" --dry-run --threads 3 >hy3.sh 2>hy3.err || fail "--threads 3"
expect_in hy3.err "warning: --threads 3 with --cpus-per-task 1: each rank runs 3 realizations on 1 CPU(s)"
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
