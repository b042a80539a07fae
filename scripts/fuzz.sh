#!/usr/bin/env bash
# The fuzz harness over thousands of cases (CI runs a few hundred, tests/tests/fuzz.rs):
# mutated scenario files (drawn from every file in configs/, with structural mutations) and
# flag sets, each through `orchestrator up`; fails on a panic, a signal, a hang, an error that
# does not name file, key path and line (or names a line that does not hold its key), a
# message that echoes a huge input, or a run that leaves anything behind. 3,000 cases take
# about 7 minutes on 2 cores.
#   scripts/fuzz.sh [CASES] [SEED]        (default 3000 cases of seed 1)
set -euo pipefail
cd "$(dirname "$0")/.."
CASES="${1:-3000}"
SEED="${2:-1}"
cargo build --release
FUZZ_CASES="$CASES" FUZZ_SEED="$SEED" cargo test --release -p e2e --test fuzz -- --nocapture
