#!/bin/bash
# Logs, every 2 s, for each running `campaign run bench/figure_of_merit/...` process: unix time,
# pid, utime + stime (clock ticks, cumulative), ticks per second, the sweep file. Stops when the
# file named by $1 (default /tmp/fom/stop) exists.
stop=${1:-/tmp/fom/stop}
tck=$(getconf CLK_TCK)
until [ -e "$stop" ]; do
  for pid in $(pgrep -f "campaign run bench/figure_of_merit"); do
    if [ -r /proc/$pid/stat ]; then
      read -r -a st < /proc/$pid/stat
      tag=$(tr '\0' ' ' < /proc/$pid/cmdline | grep -o "figure_of_merit/[a-z]*.toml")
      echo "$(date +%s.%N) $pid $(( ${st[13]} + ${st[14]} )) $tck $tag"
    fi
  done
  sleep 2
done
