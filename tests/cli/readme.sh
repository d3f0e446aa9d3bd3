#!/bin/bash
# The README's command lines as a new user types them (issue 43, item 9):
# - `campaign` is used bare only after the README says how to make it a command (its PATH line),
#   and that line, run from the repository root, makes `campaign` the built executable;
# - every command of the README's list answers `campaign help COMMAND` with its exit codes;
# - the README's Python example run by a python3 without Debian's packages (another python3
#   first on PATH) fails with a message that says to use /usr/bin/python3, not a bare
#   "No module named 'h5py'".
# Environment: SRC (source tree), BUILD (build tree), WORK (scratch).
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK" && mkdir -p "$WORK" || exit 1
README=$SRC/README.md

path_line=$(grep -n '^    export PATH="\$PWD/build/src/cli:\$PATH"$' "$README" | head -1 | cut -d: -f1)
[ -n "$path_line" ] || fail "README.md has no 'export PATH=\"\$PWD/build/src/cli:\$PATH\"' line"
first_bare=$(grep -nE '(^    (mpirun [^c]*)?|`)campaign ' "$README" | head -1 | cut -d: -f1)
[ "$first_bare" -gt "$path_line" ] ||
    fail "README.md line $first_bare uses a bare 'campaign' before its PATH line ($path_line)"

# the PATH line, run in a repository root whose build/ is this build tree
mkdir -p "$WORK/root" && ln -s "$BUILD" "$WORK/root/build"
line=$(sed -n "${path_line}p" "$README" | sed 's/^    //')
found=$(cd "$WORK/root" && eval "$line" && command -v campaign)
[ "$found" = "$WORK/root/build/src/cli/campaign" ] || fail "after '$line': campaign is '$found'"
version=$(cd "$WORK/root" && eval "$line" && campaign --version) || fail "campaign --version"
echo "ok: $line -> $found ($version)"

# every command of the README's list: `campaign help COMMAND` with exit codes
commands=$(grep -E '^    campaign [a-z]+ ' "$README" | awk '{print $2}' | sort -u)
[ "$(echo "$commands" | wc -w)" -ge 7 ] || fail "README lists only: $commands"
for c in $commands; do
    out=$(cd "$WORK/root" && eval "$line" && campaign help "$c") || fail "campaign help $c"
    grep -q '^exit codes: 0 ' <<<"$out" || fail "campaign help $c lists no exit codes"
done
echo "ok: campaign help lists exit codes for" $commands

# the README's Python example under a python3 that lacks h5py (python3 -S: no site-packages,
# as a conda or bare-venv python3 first on PATH)
awk '/^<!-- example: tests\/analysis\/store.sh runs this block -->/ {on = 1; next}
     on && /^```python/ {inside = 1; next} inside && /^```/ {exit} inside {print}' \
    "$README" >"$WORK/example.py"
[ -s "$WORK/example.py" ] || fail "no Python example found in README.md"
(cd "$SRC" && /usr/bin/python3 -S "$WORK/example.py") >"$WORK/py.out" 2>"$WORK/py.err" &&
    fail "the example ran without h5py"
grep -q "No module named 'h5py'" "$WORK/py.err" || { cat "$WORK/py.err"; fail "not about h5py"; }
grep -q "Use Debian's /usr/bin/python3" "$WORK/py.err" ||
    { cat "$WORK/py.err"; fail "the error does not say to use /usr/bin/python3"; }
echo "ok: $(tail -1 "$WORK/py.err" | cut -c1-160)..."
echo "readme.sh: passed"
