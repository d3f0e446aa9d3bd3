#!/bin/bash
# shakes.sh TOML CORE OUT SEED...: the first 10 s of discharge of the full published
# realization (D = 2.7 cm, theta 45) at each seed, one after another on one core (issue 41:
# do the shakes clear the jams as often with corrected Verlet at 25 as with gear4 at 50?).
# CAMPAIGN: the campaign binary (default build/src/cli/campaign, from the repository root).
set -euo pipefail
campaign=${CAMPAIGN:-build/src/cli/campaign}
toml=$1 core=$2 out=$3; shift 3
mkdir -p "$out"
for s in "$@"; do
    taskset -c "$core" "$campaign" simulate "$toml" --D 2.7 --theta 45 \
        --seed "$s" --json >"$out/$(basename "$toml" .toml)-$s.json" 2>/dev/null
done
