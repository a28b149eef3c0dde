#!/bin/sh
# Convergence of --temporal 64 on the static views of the quality table
# (docs/evaluation.md "Converging a static view"): the MRE per pixel against
# the references of `softgi evaluate --quality` (run that first) at frames 0,
# 3, 15, 31 and 63, per method. Writes its frames to /tmp/conv.
# METHODS overrides the methods (default: ir ir+reseed=1 iir smc), EXTRA adds
# frame options to every run (e.g. EXTRA="--vpl-cycle 32").
set -e
METHODS=${METHODS:-"ir ir+reseed=1 iir smc"}
EXTRA=${EXTRA:-}
for sc in cornell sibenik; do
  R=out/evaluate/quality/$sc/reference-b3.pfm; R1=out/evaluate/quality/$sc/reference-b1.pfm
  for m in $METHODS; do
    meth=${m%%+*}; par=""; [ "$m" != "$meth" ] && par="--param ${m#*+}"
    ref=$R  # each method against its own bounce count (app_quality.c qu__bounces)
    case $meth in iir|invtm|tcas) ref=$R1 ;; ssvp) ref=out/evaluate/quality/$sc/reference-b2.pfm ;; esac
    ./build/softgi sequence scenes/sequences/$sc-static.seq.json --indirect-only --method $meth $par --compensate on --temporal 64 $EXTRA -o /tmp/conv/$sc-$m -q
    line="$sc $m $EXTRA"
    for f in 0000 0003 0015 0031 0063; do line="$line $(./build/softgi compare /tmp/conv/$sc-$m/frame_$f.pfm $ref | awk '/^MRE/{print $2}')"; done
    echo "$line"
  done
done
