#!/usr/bin/env bash
# The reference runs of the "missions as plug-ins" refactor: runs a fixed set of scenarios with
# the binaries in BIN (default target/release) into OUT, both executors. Compare two such folders
# with `cmp` on each recording.bin (scripts/reference-runs.sh compare A B); where headers may
# differ (the resolved scenario lists more), `python3 scripts/recording-ticks-cmp.py A B RUN...`
# compares the tick records alone.
set -euo pipefail
if [ "${1:-}" = compare ]; then
  a=$2; b=$3; bad=0; n=0
  for f in "$a"/*/recording.bin; do
    name=$(basename "$(dirname "$f")"); n=$((n + 1))
    if cmp -s "$f" "$b/$name/recording.bin"; then echo "same  $name"; else echo "DIFF  $name"; bad=1; fi
  done
  echo "$n runs compared"; exit $bad
fi
BIN=${BIN:-target/release}
OUT=${1:?usage: reference-runs.sh OUT | compare A B}
mkdir -p "$OUT"
run() { # name, args...
  local name=$1; shift
  for ex in processes inprocess; do
    "$BIN/orchestrator" up --quiet --executor $ex --out "$OUT/$name-$ex" "$@" > "$OUT/$name-$ex.log" 2>&1 \
      || echo "exit $? for $name-$ex"
  done
}
for mode in BT BE BA ST SE SA; do
  for n in 20 100; do
    run search-$mode-n$n --scenario configs/search.toml --mode $mode --robots $n --loss 0.3 --delay 2 --seed 3 --max-ticks 600
  done
done
run search-BT-n50-clean --scenario configs/search.toml --robots 50 --seed 5
run roam-n50 --scenario configs/roam.toml --robots 50 --max-ticks 300 --loss 0.2 --seed 2
run roam-chaos-drop --scenario configs/roam.toml --robots 30 --max-ticks 300 --chaos 4 --on-fault drop --seed 4
run search-chaos-drop --scenario configs/search.toml --robots 30 --chaos 2 --on-fault drop --seed 6 --max-ticks 800
