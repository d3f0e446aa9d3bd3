#!/usr/bin/python3
"""Every command line of README.md and docs/usage.md, run (issue 43): the doc-test `docs.commands`.

Usage: commands.py SRC BUILD WORK   (source tree, build tree, scratch directory: emptied first)

What a command line is (the rule; docs/development.md, "The doc-test"):
- Code blocks of the two files: fenced blocks tagged ```sh, ```bash, ```shell or ```console (in a
  console block only the lines that start with "$ "), untagged fenced blocks, and indented blocks
  (a run of lines indented by 4 or more spaces after a blank line, outside fenced blocks; these
  files indent list continuations by 2 or 3 spaces). Fenced blocks of another language (```toml,
  ```python) are not command lines: the Python ones are run by tests/analysis (see their
  `<!-- ... runs this block -->` comments).
- A line indented further than its block's first line, or one after a line that ends in a
  backslash, continues the command line above it (the synopses of docs/usage.md wrap so). A line
  that starts with "#" is a comment.
- Every line of such a block is a command line unless the block is in TEXT_BLOCKS below
  (printed output, a sweep-file fragment), with its reason.

How each command line is checked:
- In document order (README.md, then docs/usage.md), each by `bash -c` in WORK/root, a scratch
  repository root: copies of campaigns/ and analysis/ (lines write beside them), WORK/root/build
  a directory of links to the build tree's entries (lines write their stores there, not into the
  real build tree), links to the other top-level entries of the source tree. Exported variables
  carry from one line to the next (the README's `export PATH=...` line is what puts `campaign` on
  PATH: the test starts with no `campaign` on PATH). HOME is WORK/home (`~/.local` is scratch).
- Environment: HOPPER_PLOTS unset (the README's quickstart draws its figures); as root
  OMPI_ALLOW_RUN_AS_ROOT(_CONFIRM)=1 (CI runs as root); OMPI_MCA_rmaps_base_oversubscribe=1 (more
  ranks than the 2 cores of CI: docs/usage.md says to start one rank more than the cores);
  PIP_NO_INDEX=1 (no network: a line that would download fails instead of hanging).
- By default a line runs as written and must exit 0. A line in INSTEAD runs the command given
  there instead (a synopsis with placeholders, a cluster submission run with --dry-run, a study
  of core-days run on the quickstart's store, a chain whose install and build parts are skipped),
  with its reason and expected exit code; a line in SKIP is not run, with its reason. Every
  `--option` a command line gives to `campaign CMD` (synopses included) must be one that
  `campaign help CMD` lists. Some lines have a CHECK (a shell condition run after them).
- A line that is neither run nor in a table cannot exist (it runs as written); an entry of a
  table that matches no line of the docs fails the test (the docs moved: update the table).
- Printed: each line with its outcome and time, then the counts run (as written / instead),
  skipped (with reasons) and failed; each line's stdout and stderr are kept in WORK/logs, and the
  end of them printed for a failed line.

The quickstart (README's first line) runs once, for real (about 1.5 min on 2 loaded cores; no
fixture holds its store), into WORK/root/build/quickstart.h5; later lines reuse that store.
"""

import os
import re
import shutil
import signal
import subprocess
import sys
import time

SHELL_LANGS = {"sh", "bash", "shell", "console"}
LINE_TIMEOUT_S = 450  # a hang's bound per line (the quickstart takes 1.5-3 min on 2 loaded cores)

# Blocks of code that are not command lines: (file, the block's first line) -> reason.
TEXT_BLOCKS = {
    ("docs/usage.md", "analysis per point (...)"):
        "the end of the quickstart's output (README's first line prints it; CHECK there)",
    ("docs/usage.md", "[fields]"): "a sweep-file fragment (TOML), not a command",
}

# Lines not run: (file, the command line) -> reason.
SKIP = {
    ("README.md", "./install-deps.sh && cmake -S . -B build -DCMAKE_BUILD_TYPE=Release && "
                  "cmake --build build -j2 && ctest --test-dir build --output-on-failure -j2"):
        "install (apt-get, sudo), build and the whole test suite, this test included: it is "
        "what CI (.ci/run) runs, every time",
}

# Lines run as another command: (file, the command line) -> (command, expected exit code, reason).
# SWEEP: the campaign tests' 12-task sweep (tests/campaign/data/mini.toml) or the quickstart;
# STORE: the quickstart's store made by the README's first line.
MINI = "tests/campaign/data/mini.toml"
QS = "build/quickstart.h5"
INSTEAD = {
    ("README.md", "./install-deps.sh && cmake -S . -B build -DCMAKE_BUILD_TYPE=Release && "
                  "cmake --build build -j2 && ./build/src/cli/campaign run campaigns/quickstart.toml "
                  "--threads 2 --store build/quickstart.h5"):
        ("./build/src/cli/campaign run campaigns/quickstart.toml --threads 2 --store "
         "build/quickstart.h5", 0,
         "its last part as written; the parts before it install (apt-get, sudo) and build the "
         "tree this test runs from"),
    # the README's list of commands (placeholders, a description after each)
    ("README.md", "campaign run SWEEP.toml run or resume a campaign (mpirun for many ranks)"):
        (f"campaign run {MINI} --store build/mini.h5 --threads 2 --no-plots", 0,
         "SWEEP.toml: the 12-task mini sweep (the quickstart's figures are drawn by line 1)"),
    ("README.md", "campaign status STORE.h5 progress, rate, ETA, failures (also during a run)"):
        (f"campaign status {QS}", 0, "STORE.h5: the quickstart's store"),
    ("README.md", "campaign analyze STORE.h5 statistics and fits, written into the store"):
        (f"campaign analyze {QS}", 0, "STORE.h5: the quickstart's store"),
    ("README.md", "campaign plot STORE.h5 figures for papers (png, pdf, svg)"):
        ("campaign plot build/mini.h5", 0, "STORE.h5: the mini sweep's store"),
    ("README.md", "campaign export STORE.h5 --csv DIR CSV tables (--vtk DIR: VTK field maps)"):
        (f"campaign export {QS} --csv build/csv", 0, "STORE.h5: the quickstart's store"),
    ("README.md", "campaign simulate ... one realization: a new one, or a stored one again"):
        ("campaign simulate campaigns/quickstart.toml --D 2.5 --theta 60 --seed 1", 0,
         "...: the quickstart's scene at one outlet"),
    ("README.md", "campaign submit SWEEP.toml a campaign on Slurm that resubmits itself"):
        ("campaign submit campaigns/quickstart.toml --dry-run", 0,
         "--dry-run: no Slurm here (prints the batch script and the estimate)"),
    ("README.md", "campaign cite STORE.h5 what to cite for the store: plain text and BibTeX"):
        (f"campaign cite {QS}", 0, "STORE.h5: the quickstart's store"),
    ("README.md", "campaign merge A.h5 B.h5 --store C.h5 one store from stores of one campaign "
                  "(two machines)"):
        (f"campaign merge {QS} {QS} --store build/merged.h5", 0,
         "A.h5, B.h5: the quickstart's store twice (a store merged with itself)"),
    # Clusters
    ("README.md", "mpirun -np 9 campaign run SWEEP.toml # rank 0 hands out work and writes; "
                  "8 workers"):
        (f"mpirun -np 9 campaign run {MINI} --store build/mini-mpi.h5 --no-plots", 0,
         "SWEEP.toml: the mini sweep, on 9 ranks (oversubscribed)"),
    ("README.md", "campaign submit SWEEP.toml --nodes 2 --ntasks 64 --time 24:00:00 "
                  "# Slurm, resubmits itself"):
        ("campaign submit campaigns/quickstart.toml --nodes 2 --ntasks 64 --time 24:00:00 "
         "--dry-run", 0, "SWEEP.toml: the quickstart; --dry-run: no Slurm here"),
    # Reproducing the published study
    ("README.md", "campaign submit campaigns/paper/survival.toml --nodes 2 --ntasks 64 "
                  "--time 24:00:00"):
        ("campaign submit campaigns/paper/survival.toml --nodes 2 --ntasks 64 --time 24:00:00 "
         "--dry-run", 0, "--dry-run: no Slurm here (the batch script and the estimate)"),
    ("README.md", "campaign status campaigns/paper/survival.h5"):
        (f"campaign status {QS}", 0,
         "the survival study's store takes core-days (the submit line above): the quickstart's"),
    ("README.md", "campaign plot campaigns/paper/survival.h5 --format pdf --width column"):
        (f"campaign plot {QS} --format pdf --width column", 0,
         "the survival study's store takes core-days: the quickstart's"),
    # docs/usage.md's synopses
    ("docs/usage.md", "campaign run SWEEP.toml [--store PATH] [--progress-interval S] [--grace S] "
                      "[--threads N] [--flush-interval S] [--worker-timeout S] [--no-file-locking] "
                      "[--deadline T] [--checkpoint-interval S] [--no-checkpoints] "
                      "[--max-deaths N] [--dry-run] [--allow-mixed] [--no-plots]"):
        (f"campaign run campaigns/quickstart.toml --store {QS} --dry-run", 0,
         "a synopsis: the quickstart's store, resumed with --dry-run (nothing to run)"),
    ("docs/usage.md", "mpirun -np N campaign run SWEEP.toml ... # rank 0 = master, ranks "
                      "1..N-1 = workers"):
        (f"mpirun -np 3 campaign run campaigns/quickstart.toml --store {QS} --no-plots", 0,
         "a synopsis: N = 3, the quickstart's store resumed (nothing to run)"),
    ("docs/usage.md", "campaign status STORE.h5 [--json] # progress and failures, also during "
                      "a run"):
        (f"campaign status {QS} --json", 0, "a synopsis: the quickstart's store"),
    ("docs/usage.md", "campaign merge A.h5 B.h5 ... --store C.h5"):
        ("campaign merge build/mini.h5 build/mini-mpi.h5 --store build/mini-merged.h5", 0,
         "a synopsis: the mini sweep's stores of 2 threads and 9 ranks (the same realizations)"),
    ("docs/usage.md", "campaign analyze STORE.h5 [--json] [--no-write]"):
        (f"campaign analyze {QS} --json --no-write", 0, "a synopsis: the quickstart's store"),
    ("docs/usage.md", "campaign plot STORE.h5 [--out DIR] [--format png,pdf,svg] "
                      "[--width page|column]"):
        ("campaign plot build/mini.h5 --out build/mini-svg --format svg --width column", 0,
         "a synopsis: the mini sweep's store"),
    ("docs/usage.md", "campaign export STORE.h5 [--csv DIR] [--vtk DIR] # one of the two at least"):
        (f"campaign export {QS} --csv build/quickstart-csv", 0,
         "a synopsis: the quickstart's store (it has no fields for --vtk)"),
    ("docs/usage.md", "campaign export STORE.h5 --snapshot FILE # the store as it stands (store.md)"):
        (f"campaign export {QS} --snapshot build/snapshot.h5", 0,
         "a synopsis: the quickstart's store"),
    ("docs/usage.md", "campaign cite STORE.h5 [--bibtex | --text]"):
        (f"campaign cite {QS} --bibtex", 0, "a synopsis: the quickstart's store"),
    ("docs/usage.md", "campaign simulate SWEEP.toml --D CM --theta DEG --seed N [--json] "
                      "[--progress] [--snapshots DIR] [--snapshot-interval S] "
                      "[--snapshot-format F]"):
        ("campaign simulate campaigns/quickstart.toml --D 2.1 --theta 60 --seed 7 --json "
         "--snapshots build/frames --snapshot-interval 0.5", 0,
         "a synopsis: the quickstart's scene"),
    ("docs/usage.md", "campaign simulate --store STORE.h5 --point LABEL --realization I "
                      "[the same options]"):
        (f"campaign simulate --store {QS} --point 'D_cm=2.5 theta_deg=60' --realization 3", 0,
         "a synopsis: a realization of the quickstart's store again"),
}

# Conditions checked after a line (in its environment, from the root): (file, line) -> shell.
CHECK = {
    ("README.md", "export PATH=\"$PWD/build/src/cli:$PATH\""):
        '[ "$(command -v campaign)" = "$PWD/build/src/cli/campaign" ]',
    next(k for k in INSTEAD if k[1].startswith("./install-deps.sh")):
        "test -s build/quickstart.h5 -a -s build/quickstart.h5.journal -a "
        "-s build/quickstart_plots/survival.png && grep -q '^analysis per point' \"$LOG.out\"",
    ("README.md", "cmake --install build --prefix ~/.local # campaign, libraries, headers, "
                  "hopperConfig.cmake"):
        "~/.local/bin/campaign --version && test -s ~/.local/lib/cmake/hopper/hopperConfig.cmake",
    ("README.md", "/usr/bin/python3 -m venv --system-site-packages ENV && ENV/bin/pip install "
                  "--no-build-isolation ./analysis"):
        "ENV/bin/python -c 'from hopper_analysis import open_store' && test -x ENV/bin/hopper-plot",
}

DOCS = ["README.md", "docs/usage.md"]


def norm(s):
    return " ".join(s.split())


def indent_of(line):
    return len(line) - len(line.lstrip(" "))


def command_lines(path, rel):
    """Yields (line number, command line, block key) for every command line of the file, and
    records the non-command blocks (returned by the second value of the pair)."""
    lines = open(path, encoding="utf-8").read().split("\n")
    blocks = []  # (kind, first line number, [(number, text)])
    i, prev_blank = 0, True
    while i < len(lines):
        m = re.match(r"^```\s*([\w+-]*)", lines[i])
        if m:
            lang, body, start = m.group(1).lower(), [], i + 1
            i += 1
            while i < len(lines) and not lines[i].startswith("```"):
                body.append((i + 1, lines[i]))
                i += 1
            i += 1
            blocks.append((lang or "untagged", start, body))
            prev_blank = False
            continue
        if prev_blank and lines[i].startswith("    ") and lines[i].strip():
            body, start = [], i + 1
            while i < len(lines):
                if lines[i].startswith("    "):
                    body.append((i + 1, lines[i]))
                elif lines[i].strip() == "" and i + 1 < len(lines) and \
                        lines[i + 1].startswith("    "):
                    pass
                else:
                    break
                i += 1
            blocks.append(("indented", start, body))
            continue
        prev_blank = lines[i].strip() == ""
        i += 1

    cmds, others = [], []
    for kind, start, body in blocks:
        if kind not in SHELL_LANGS | {"indented", "untagged"}:
            others.append((rel, start, kind, None))
            continue
        texts = [(n, t) for n, t in body if t.strip()]
        if not texts:
            continue
        first = norm(texts[0][1])
        if (rel, first) in TEXT_BLOCKS:
            others.append((rel, start, "text", (rel, first)))
            continue
        base = indent_of(texts[0][1])
        logical = []  # [line number, text]
        cont = False
        for n, t in texts:
            s = t.strip()
            if kind == "console":
                if not s.startswith("$ ") and not cont:
                    continue
                s = s[2:] if s.startswith("$ ") else s
            if logical and (cont or indent_of(t) > base):
                logical[-1][1] += " " + s
            elif s.startswith("#"):
                continue
            else:
                logical.append([n, s])
            cont = s.endswith("\\")
            if cont:
                logical[-1][1] = logical[-1][1][:-1]
        for n, s in logical:
            cmds.append((rel, n, norm(s)))
    return cmds, others


def campaign_options(cmd):
    """(subcommand, [--options]) for each `campaign SUB ...` in a command line."""
    out = []
    for part in re.split(r"&&|\|\||;|\|", cmd.split(" #")[0]):
        m = re.search(r"(?:^|\s|/)campaign\s+([a-z]+)\b(.*)", part)
        if m:
            out.append((m.group(1), re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", m.group(2))))
    return out


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__.split("\n")[2])
    src, build, work = (os.path.abspath(a) for a in sys.argv[1:])
    t_start = time.monotonic()
    shutil.rmtree(work, ignore_errors=True)
    root, logs, home = (os.path.join(work, d) for d in ("root", "logs", "home"))
    for d in (root, logs, home, os.path.join(root, "build")):
        os.makedirs(d)

    # the scratch root
    written_beside = {"campaigns", "analysis"}
    for e in sorted(os.listdir(src)):
        if e in (".git", "build") or e.startswith("build-"):
            continue
        if e in written_beside:
            shutil.copytree(os.path.join(src, e), os.path.join(root, e),
                            ignore=shutil.ignore_patterns("__pycache__", "*.h5", "*.journal"))
        else:
            os.symlink(os.path.join(src, e), os.path.join(root, e))
    for e in sorted(os.listdir(build)):
        if e in ("install_manifest.txt", "Testing") or ".h5" in e or e.startswith("quickstart"):
            continue
        os.symlink(os.path.join(build, e), os.path.join(root, "build", e))

    env = dict(os.environ)
    env.pop("HOPPER_PLOTS", None)
    # no `campaign` on PATH before the README's PATH line
    env["PATH"] = ":".join(d for d in env.get("PATH", "/usr/bin:/bin").split(":")
                           if d and not os.access(os.path.join(d, "campaign"), os.X_OK))
    env.update(HOME=home, PIP_NO_INDEX="1", OMPI_MCA_rmaps_base_oversubscribe="1",
               MPLBACKEND="Agg")
    if os.geteuid() == 0:
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    envfile = os.path.join(work, "env.sh")
    with open(envfile, "w") as f:
        for k, v in env.items():
            if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", k):
                f.write("export %s=%s\n" % (k, "'" + v.replace("'", "'\\''") + "'"))

    # the help text of every campaign subcommand, for the options check
    helps = {}

    def help_of(sub):
        if sub not in helps:
            exe = os.path.join(build, "src", "cli", "campaign")
            p = subprocess.run([exe, "help", sub], capture_output=True, text=True, env=env)
            helps[sub] = p.stdout + p.stderr if p.returncode == 0 else None
        return helps[sub]

    cmds, others = [], []
    for rel in DOCS:
        c, o = command_lines(os.path.join(src, rel), rel)
        cmds += c
        others += o

    used = set()
    ran = instead = skipped = 0
    failed = []
    skips = []
    print("doc-test: %d command lines in %s (%d other code blocks)" %
          (len(cmds), " and ".join(DOCS), len(others)))
    for rel, start, kind, key in others:
        if key:
            used.add(key)
        print("  not commands: %s:%d (%s)%s" % (rel, start, kind,
                                                ": " + TEXT_BLOCKS[key] if key else ""))

    def run_shell(cmd, log):
        script = ('. "$1"; cd "$2" || exit 99; LOG="$3"; set -o pipefail; eval "$4"; rc=$?; '
                  'export -p >"$1.new" && mv "$1.new" "$1"; exit $rc')
        with open(log + ".out", "ab") as out, open(log + ".err", "ab") as err:
            p = subprocess.Popen(["bash", "-c", script, "doctest", envfile, root, log, cmd],
                                 stdout=out, stderr=err, stdin=subprocess.DEVNULL,
                                 env=env, start_new_session=True)
            try:
                return p.wait(timeout=LINE_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
                return "timeout (%d s)" % LINE_TIMEOUT_S

    for idx, (rel, n, line) in enumerate(cmds, 1):
        key = (rel, line)
        where = "%s:%d" % (rel, n)
        problems = []
        for sub, opts in campaign_options(line):
            h = help_of(sub)
            if h is None:
                problems.append("`campaign help %s` fails: no such command" % sub)
                continue
            for o in opts:
                if not re.search(r"(?<![\w-])%s(?![\w-])" % re.escape(o), h):
                    problems.append("`campaign help %s` lists no %s" % (sub, o))
        if key in SKIP:
            used.add(key)
            skipped += 1
            skips.append((where, line, SKIP[key]))
            print("[%2d] skip    %s  %s\n          why: %s" % (idx, where, line, SKIP[key]))
            if problems:
                failed.append((where, line, "; ".join(problems), None))
                print("          FAILED: " + "; ".join(problems))
            continue
        if key in INSTEAD:
            used.add(key)
            cmd, want, why = INSTEAD[key]
            label = "instead"
            # the command run instead is the same command: the same `campaign` subcommands, and
            # under mpirun where the line is
            if [c for c, _ in campaign_options(cmd)] != [c for c, _ in campaign_options(line)] \
                    or cmd.startswith("mpirun ") != line.startswith("mpirun "):
                problems.append("the command run instead is not the line's command: " + cmd)
        else:
            cmd, want, why = line, 0, None
            label = "run"
        log = os.path.join(logs, "%02d" % idx)
        t0 = time.monotonic()
        rc = run_shell(cmd, log)
        dt = time.monotonic() - t0
        if key in CHECK:
            used.add(key)
        if rc == want and key in CHECK:
            with open(log + ".out", "ab") as f:
                f.write(b"\n--- check: " + CHECK[key].encode() + b"\n")
            crc = run_shell(CHECK[key], log)
            if crc != 0:
                problems.append("check failed (rc %s): %s" % (crc, CHECK[key]))
        if rc != want:
            problems.insert(0, "exit code %s, expected %d" % (rc, want))
        status = "ok" if not problems else "FAILED"
        print("[%2d] %-7s %s  %s" % (idx, label, where, line))
        if why:
            print("          runs: %s\n          why:  %s" % (cmd, why))
        print("          %s (exit %s, %.1f s; log %s.out/.err)" % (status, rc, dt, log))
        if problems:
            failed.append((where, line, "; ".join(problems), log))
            for p in problems:
                print("          " + p)
            for ext in (".out", ".err"):
                tail = open(log + ext, errors="replace").read().splitlines()[-25:]
                if tail:
                    print("          --- end of %s%s:" % (os.path.basename(log), ext))
                    print("\n".join("          | " + t for t in tail))
        if label == "run":
            ran += 1
        else:
            instead += 1

    stale = [k for k in list(TEXT_BLOCKS) + list(SKIP) + list(INSTEAD) + list(CHECK)
             if k not in used]
    for k in stale:
        failed.append(("%s" % k[0], k[1], "a table entry that matches no line of the docs "
                       "(the docs changed: update the table in %s)" % os.path.basename(__file__),
                       None))
        print("FAILED: table entry for %s matches no line: %s" % k)

    print("\ndoc-test summary: %d command lines; run %d (%d as written, %d instead, as the table "
          "says); skipped %d; failed %d; %.0f s" % (len(cmds), ran + instead, ran, instead,
                                                    skipped, len(failed),
                                                    time.monotonic() - t_start))
    for where, line, why in skips:
        print("  skipped %s: %s\n          why: %s" % (where, line, why))
    for where, line, why, log in failed:
        print("  failed  %s: %s\n          %s" % (where, line, why))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
