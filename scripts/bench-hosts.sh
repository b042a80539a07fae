#!/usr/bin/env bash
# The tick across hosts (issue 41, BENCHMARKS.md "Across hosts"): a roam swarm of N robots
# split evenly over NS network namespaces on this machine (the world's and NS-1 hosts', each
# host joined to the world's by a veth pair), with no added delay and with `tc netem` delays
# of 0.5 and 2 ms each way, against the same swarm on one host. Prints one row per case: the
# tick's p50 on one host and across hosts, the link's round-trip time (TCP, measured beside
# it) and the target (one host + 20 % + one round trip). Needs root, iproute2 and python3;
# build first: cargo build --release.
#
#   scripts/bench-hosts.sh [ROBOTS...]   (default: 50 200)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=target/release/orchestrator
TICKS=${TICKS:-300}
REPS=${REPS:-3}   # runs per case; each figure is the median of their tick p50s
PORT=7447
ROBOTS=("${@:-50 200}")
[ "$(id -u)" = 0 ] || { echo "needs root (ip netns)" >&2; exit 2; }
[ -x "$BIN" ] || { echo "build first: cargo build --release" >&2; exit 2; }
TMP=$(mktemp -d)
NETS=()
cleanup() {
  local ns
  for ns in "${NETS[@]}"; do ip netns del "$ns" 2>/dev/null || true; done
  rm -rf "$TMP"
}
trap cleanup EXIT

# make_net HOSTS: namespaces swbw, swbh1..swbhHOSTS; host h's link is 10.99.h.1 <-> 10.99.h.2.
make_net() {
  local ns h
  for ns in "${NETS[@]}"; do ip netns del "$ns" 2>/dev/null || true; done
  NETS=(swbw)
  ip netns add swbw
  ip -n swbw link set lo up
  for h in $(seq 1 "$1"); do
    NETS+=("swbh$h")
    ip netns add "swbh$h"
    ip -n "swbh$h" link set lo up
    ip link add "swba$h" netns swbw type veth peer name "swbb$h" netns "swbh$h"
    ip -n swbw addr add "10.99.$h.1/24" dev "swba$h"
    ip -n "swbh$h" addr add "10.99.$h.2/24" dev "swbb$h"
    ip -n swbw link set "swba$h" up
    ip -n "swbh$h" link set "swbb$h" up
  done
}

# netem NS DEV MS: a netem delay of MS ms on DEV's egress (0: none).
netem() {
  tc -n "$1" qdisc del dev "$2" root 2>/dev/null || true
  [ "$3" = 0 ] || tc -n "$1" qdisc add dev "$2" root netem delay "${3}ms"
}

# delay HOSTS MS: MS ms each way on every link.
delay() {
  for h in $(seq 1 "$1"); do
    netem swbw "swba$h" "$2"
    netem "swbh$h" "swbb$h" "$2"
  done
}

# rtt_ms: median TCP round trip (64-byte messages, TCP_NODELAY) from the world to host 1.
rtt_ms() {
  local py='
import socket, statistics, sys, time
if sys.argv[1] == "serve":
    s = socket.socket(); s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.bind(("0.0.0.0", 7999)); s.listen(1); c, _ = s.accept()
    c.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    while (d := c.recv(64)): c.sendall(d)
else:
    c = socket.create_connection((sys.argv[1], 7999))
    c.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    t = []
    for _ in range(200):
        a = time.perf_counter(); c.sendall(b"x" * 64); n = 0
        while n < 64: n += len(c.recv(64))
        t.append(time.perf_counter() - a)
    print(f"{statistics.median(t) * 1e3:.3f}")
'
  ip netns exec swbh1 python3 -c "$py" serve &
  local srv=$!
  sleep 0.3
  ip netns exec swbw python3 -c "$py" 10.99.1.2
  wait "$srv" 2>/dev/null || true
}

# scenario FILE N HOSTS: roam, N robots, the last HOSTS/(HOSTS+1) of them on hosts h1..
scenario() {
  local file=$1 n=$2 hosts=$3
  {
    [ "$hosts" = 0 ] || echo "hosts_listen = \"tcp/0.0.0.0:$PORT\""
    printf '[run]\nbehaviour = "roam"\nrobots = %s\nmax_ticks = %s\nseed = 5\n' "$n" "$TICKS"
    printf '[runtime]\nstartup_timeout_s = 60\n'
    local per=$((n / (hosts + 1)))
    for h in $(seq 1 "$hosts"); do
      local from=$((h * per)) to=$(((h + 1) * per))
      [ "$h" = "$hosts" ] && to=$n
      printf '[[hosts]]\nname = "h%s"\nrobots = "%s..%s"\n' "$h" "$from" "$to"
    done
  } >"$file"
}

# p50_ms DIR...: the median over the runs in DIR... of each run's tick p50, in ms.
p50_ms() {
  python3 -c "import json,statistics,sys; print(f\"{statistics.median(json.load(open(d + '/summary.json'))['tick_time']['p50_us'] for d in sys.argv[1:])/1e3:.3f}\")" "$@"
}

printf '%-7s %-4s %-9s %-9s %-12s %-13s %-10s %s\n' robots ns netem_ms rtt_ms one_host_ms across_ms target_ms ok
for n in ${ROBOTS[@]}; do
  for ns in 2 4; do
    hosts=$((ns - 1))
    make_net "$hosts"
    scenario "$TMP/one.toml" "$n" 0
    for r in $(seq 1 "$REPS"); do
      ip netns exec swbw "$BIN" up --quiet --scenario "$TMP/one.toml" --out "$TMP/one-$n-$ns-$r" >/dev/null || true
    done
    one=$(p50_ms "$TMP"/one-"$n-$ns"-*)
    for d in 0 0.5 2; do
      if ! delay "$hosts" "$d" 2>/dev/null; then
        printf '%-7s %-4s %-9s (tc netem unavailable here: no sch_netem in this kernel)\n' "$n" "$ns" "$d"
        continue
      fi
      rtt=$(rtt_ms)
      scenario "$TMP/across.toml" "$n" "$hosts"
      for r in $(seq 1 "$REPS"); do
        pids=()
        for h in $(seq 1 "$hosts"); do
          ip netns exec "swbh$h" "$BIN" host --join "tcp/10.99.$h.1:$PORT" --name "h$h" --wait 120 2>/dev/null &
          pids+=($!)
        done
        out="$TMP/across-$n-$ns-$d-$r"
        ip netns exec swbw "$BIN" up --quiet --scenario "$TMP/across.toml" --out "$out" >/dev/null || true
        wait "${pids[@]}" 2>/dev/null || true
        cmp -s "$TMP/one-$n-$ns-1/recording.bin" "$out/recording.bin" ||
          echo "RECORDINGS DIFFER ($n robots, $ns ns, $d ms)" >&2
      done
      across=$(p50_ms "$TMP"/across-"$n-$ns-$d"-*)
      python3 - "$n" "$ns" "$d" "$rtt" "$one" "$across" <<'EOF'
import sys
n, ns, d, rtt, one, across = sys.argv[1:]
target = float(one) * 1.2 + float(rtt)
ok = "yes" if float(across) <= target else "no"
print(f"{n:<7} {ns:<4} {d:<9} {rtt:<9} {one:<12} {across:<13} {target:<10.3f} {ok}")
EOF
    done
  done
done
