#!/bin/bash
# pairs.sh A B N: A and B at once, one per core, swapped each pair
A=$1; B=$2; N=$3
for p in $(seq 1 $N); do
  if [ $((p%2)) = 1 ]; then ca=0; cb=1; else ca=1; cb=0; fi
  taskset -c $ca ./$A --repeats 3 --steps 2000 > out_${A}_${B}_$p.A 2>&1 &
  taskset -c $cb ./$B --repeats 3 --steps 2000 > out_${A}_${B}_$p.B 2>&1 &
  wait
  echo "pair $p: $A core $ca / $B core $cb"
  grep -E "^settled|^discharge D" out_${A}_${B}_$p.A | sed "s/^/  $A  /"
  grep -E "^settled|^discharge D" out_${A}_${B}_$p.B | sed "s/^/  $B  /"
done
