#!/bin/sh
# Appends "PID CPU_TICKS" (user + system, /proc/PID/stat fields 14 and 15,
# in sysconf(_SC_CLK_TCK) ticks) of the nearest `liggghts` ancestor to file
# $1.  in.capdem.liggghts calls it through `shell` before and after each
# timed run, so that the timed segment's CPU time is known as LAMMPS's
# "% CPU use" gives it: other jobs on a shared machine disturb it far less
# than the wall time.  Only rank 0 runs `shell`: it stamps its own time.
p=$$
while [ "$p" -gt 1 ]; do
  if [ "$(cat /proc/$p/comm)" = liggghts ]; then
    awk -v p="$p" '{ print p, $14 + $15 }' /proc/$p/stat >> "$1"
    exit 0
  fi
  p=$(awk '{ print $4 }' /proc/$p/stat)
done
echo "cpu_stamp.sh: no liggghts process above $$" >&2
exit 1
