#!/usr/bin/env bash
# Soak test (not part of CI): one long run with restarts and about 100 random SIGKILLs of agents;
# afterwards /dev/shm and the process table must hold nothing of it.
#
#   scripts/soak.sh [ROBOTS] [TICKS] [KILLS_PER_100_TICKS]
#
# Defaults: 20 robots, 11000 ticks, 1 kill per 100 ticks (~100-110 kills). It runs the roam
# scenario (configs/roam.toml): a search run would end when its targets are found.
set -euo pipefail
cd "$(dirname "$0")/.."
robots=${1:-20}
ticks=${2:-11000}
rate=${3:-1}
cargo build --release -q
out=$(mktemp -d /tmp/swarm-soak.XXXXXX)
before_shm=$(ls /dev/shm | grep -c '^sw' || true)
start=$(date +%s.%N)
./target/release/orchestrator up --quiet --scenario configs/roam.toml --robots "$robots" --max-ticks "$ticks" \
  --chaos "$rate" --on-fault restart --max-restarts 1000000 --out "$out/run"
end=$(date +%s.%N)
sleep 0.5
left_shm=$(ls /dev/shm | grep '^sw' || true)
left_procs=$(pgrep -af "$out/run" || true)
python3 - "$out/run/summary.json" "$start" "$end" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
f = s["faults"]
restarted = [x for x in f if x["restarted_tick"] is not None]
gaps = [x["restarted_tick"] - x["detected_tick"] for x in restarted]
print(f"robots {s['robots']}  ticks {s['ticks']}  wall {float(sys.argv[3]) - float(sys.argv[2]):.1f} s  "
      f"steady {s['steady_ticks_per_second']:.0f} ticks/s")
print(f"kills {len(f)}  restarted {len(restarted)}  alive at end {s['alive_at_end']}")
if gaps:
    gaps.sort()
    print(f"ticks from death to restart: median {gaps[len(gaps)//2]}  max {gaps[-1]}")
PY
if [ -n "$left_shm" ] || [ -n "$left_procs" ]; then
  echo "LEFT BEHIND: shm [$left_shm] processes [$left_procs]"
  exit 1
fi
echo "nothing left in /dev/shm (was $before_shm sw* entries before) or in the process table"
rm -rf "$out"
