#!/bin/bash
# par.sh OLD_CAMPAIGN NEW_CAMPAIGN OLD_TOML NEW_TOML D THETA PAIRS OUT [TAG]
# One whole realization (campaign simulate --seed SEED --json; SEED from the environment,
# default 1) of each build at once, one per core, the cores swapped each pair; wall seconds to
# OUT/times (issue 41). FIRST (default 1): the number of the first pair (odd: 0.4.0 on core 0).
set -euo pipefail
old=$1 new=$2 otoml=$3 ntoml=$4 D=$5 th=$6 pairs=$7 out=$8 tag=${9:-run} seed=${SEED:-1} first=${FIRST:-1}
mkdir -p "$out"
one() { # side campaign toml pair core
    local s e
    s=$(date +%s.%N)
    taskset -c "$5" "$2" simulate "$3" --D "$D" --theta "$th" --seed "$seed" --json >"$out/$tag-$1-$4.json" 2>/dev/null
    e=$(date +%s.%N)
    echo "$tag $1 pair $4 core $5 D $D theta $th seed $seed wall $(echo "$e - $s" | bc)" >>"$out/times"
}
for p in $(seq "$first" $((first + pairs - 1))); do
    if [ $((p % 2)) = 1 ]; then co=0 cn=1; else co=1 cn=0; fi
    one old "$old" "$otoml" "$p" "$co" &
    one new "$new" "$ntoml" "$p" "$cn" &
    wait
done
