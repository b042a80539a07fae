#!/bin/bash
# usage: scripts/shm-peak.sh BINDIR TAG UP_ARGS...
# Runs `BINDIR/orchestrator up --quiet UP_ARGS` with a fixed SWARM_RUN_ID and samples the
# run's /dev/shm use every 0.25 s (scripts/shm-peak.py): the peak resident size (du: blocks
# allocated) and the peak apparent size (file lengths), and at the resident peak a breakdown
# by service kind (air, sense, act, control, barrier, other: iceoryx2's node and service
# folder, status). Then the summary's start-up, ticks/s and message counters (BENCHMARKS.md
# sections 8 and 10).
BIN=$1; TAG=$2; shift 2
DIR=$(cd "$(dirname "$0")" && pwd)
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
# The old sampler beside it (du alone, cheap): a cross-check of the peak.
( MAX=0; while kill -0 $P 2>/dev/null; do
    K=$(du -sk /dev/shm/${PFX}* 2>/dev/null | awk '{s+=$1} END {print s+0}')
    [ "$K" -gt "$MAX" ] && MAX=$K; sleep 0.25
  done; echo "du_loop_max_kib=$MAX" ) &
D=$!
python3 "$DIR/shm-peak.py" $P $PFX
wait $P; echo "rc=$?"; wait $D
python3 -c "
import json; s=json.load(open('$OUT/summary.json'))
print('startup_s', s.get('startup_seconds'), 'wall_s', s.get('wall_seconds'), 'ticks', s.get('ticks'), 'steady_tps', s.get('steady_ticks_per_second'), 'p50_us', s['tick_time']['p50_us'])
print('messages', s['messages'])"
