#!/bin/bash
# usage: scripts/shm-peak.sh BINDIR TAG UP_ARGS...
# Runs `BINDIR/orchestrator up --quiet UP_ARGS` with a fixed SWARM_RUN_ID, samples the run's
# /dev/shm use (du of /dev/shm/<run prefix>*) every 0.25 s and prints the peak, then the
# summary's start-up, ticks/s and message counters (BENCHMARKS.md section 8).
BIN=$1; TAG=$2; shift 2
ID=radio-$TAG-$$
PFX=$(python3 -c "
h=0xcbf29ce484222325
for b in '$ID'.encode():
    h^=b; h=(h*0x100000001b3)&0xffffffffffffffff
print('sw%010x_'%(h&0xffffffffff))")
OUT=${TMPDIR:-/tmp}/shm-peak-$TAG
rm -rf $OUT; mkdir -p "$(dirname "$OUT")"
SWARM_RUN_ID=$ID $BIN/orchestrator up --quiet --out $OUT "$@" > $OUT.up.txt 2>&1 &
P=$!
MAX=0
while kill -0 $P 2>/dev/null; do
  K=$(du -sk /dev/shm/${PFX}* 2>/dev/null | awk '{s+=$1} END {print s+0}')
  [ "$K" -gt "$MAX" ] && MAX=$K
  sleep 0.25
done
wait $P; echo "rc=$?"
echo "shm_max_kib=$MAX"
python3 -c "
import json; s=json.load(open('$OUT/summary.json'))
print('startup_s', s.get('startup_seconds'), 'wall_s', s.get('wall_seconds'), 'ticks', s.get('ticks'), 'steady_tps', s.get('steady_ticks_per_second'), 'p50_us', s['tick_time']['p50_us'])
print('messages', s['messages'])"
