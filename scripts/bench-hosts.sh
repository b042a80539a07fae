#!/usr/bin/env bash
# The tick across hosts (issue 41, BENCHMARKS.md "Across hosts"): a thin wrapper of
# `orchestrator bench tick --hosts-only` (orchestrator/src/bench/hosts/), which splits a roam
# swarm of N robots evenly over 2 and 4 network namespaces joined by veth pairs, with no added
# delay and with `tc netem` delays of 0.5 and 2 ms each way, against the same swarm on one
# host, and prints one row per case: the tick's p50 on one host and across hosts, the link's
# round trip (TCP, measured beside it) and the target (one host + 20 % + one round trip).
# Needs root and iproute2 (otherwise the bench says why and measures nothing); build first:
# cargo build --release.
#
#   scripts/bench-hosts.sh [ROBOTS...]   (default: 50 200)
#   TICKS (default 2000; fewer above 100 robots, as bench tick does), REPS (runs per figure,
#   default 3)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=target/release/orchestrator
[ -x "$BIN" ] || { echo "build first: cargo build --release" >&2; exit 2; }
ROBOTS=("${@:-50 200}")
robots=$(echo ${ROBOTS[@]} | tr ' ' ',')
exec "$BIN" bench tick --hosts-only --robots "$robots" --ticks "${TICKS:-2000}" \
  --hosts 2,4 --hosts-runs "${REPS:-3}"
