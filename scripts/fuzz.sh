#!/usr/bin/env bash
# The fuzz harness over thousands of cases (CI runs a few hundred, tests/tests/fuzz.rs):
# mutated scenario files and flag sets, each through `orchestrator up`; fails on a panic, a
# signal, a hang, an error that does not say where, or a run that leaves anything behind.
#   scripts/fuzz.sh [CASES] [SEED]        (default 3000 cases of seed 1)
set -euo pipefail
cd "$(dirname "$0")/.."
CASES="${1:-3000}"
SEED="${2:-1}"
cargo build --release
FUZZ_CASES="$CASES" FUZZ_SEED="$SEED" cargo test --release -p e2e --test fuzz -- --nocapture
