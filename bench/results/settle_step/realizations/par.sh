#!/bin/bash
# par.sh SCENE D THETA PAIRS: 0.4.0 and HEAD (settle at delta 35) at once, one per core, swapped each pair
sc=$1 D=$2 th=$3 pairs=$4
O=/work/runs/timing
OLD=/work/v040/build/src/cli/campaign
NEW=/work/main/build/src/cli/campaign
for p in $(seq 1 $pairs); do
  if [ $((p % 2)) = 1 ]; then co=0; cn=1; else co=1; cn=0; fi
  ( s=$(date +%s.%N); taskset -c $co $OLD simulate /work/main/campaigns/paper/$sc.toml --D $D --theta $th --seed 1 --json > $O/$sc-old-$p.json 2>/dev/null; e=$(date +%s.%N); echo "old pair $p core $co wall $(echo "$e - $s" | bc)" >> $O/$sc.times ) &
  ( s=$(date +%s.%N); taskset -c $cn $NEW simulate $O/$sc-sd35.toml --D $D --theta $th --seed 1 --json > $O/$sc-new-$p.json 2>/dev/null; e=$(date +%s.%N); echo "new pair $p core $cn wall $(echo "$e - $s" | bc)" >> $O/$sc.times ) &
  wait
done
