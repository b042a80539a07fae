#!/usr/bin/env bash
# The test command of README.md, for a fresh clone on a machine with only Rust (rustup) and
# Debian's apt: installs what the tests need when it is missing, then checks formatting and
# lints, builds, and runs every test (unit tests and end-to-end tests with real processes).
# .ci/run calls it.
#
# What the tests need beyond crates.io is one `need_*` function each, listed in NEEDS in the
# order they run: to add one (a Python venv, ...), write its function and list it.
set -euo pipefail
cd "$(dirname "$0")/.."

# Installs Debian packages (as root, or with sudo); `apt-get update` once per run of this script.
apt_updated=""
apt_install() {
  local sudo=""
  [ "$(id -u)" = 0 ] || sudo="sudo"
  if [ -z "$apt_updated" ]; then
    $sudo apt-get update -q
    apt_updated=1
  fi
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q "$@"
}

# cargo fmt and cargo clippy (rustup's default profile has them; a minimal one does not).
need_rust_tools() {
  if ! cargo fmt --version >/dev/null 2>&1 || ! cargo clippy --version >/dev/null 2>&1; then
    rustup component add rustfmt clippy
  fi
}

# The viewer's e2e tests (tests/tests/viewer.rs) screenshot pages in a real headless browser.
need_chromium() {
  command -v chromium >/dev/null || apt_install chromium
}

# The Ctrl-C test (tests/tests/cli.rs) runs `orchestrator up` in a real terminal.
need_tmux() {
  command -v tmux >/dev/null || apt_install tmux
}

# The export test (tests/tests/export.rs) reads Foxglove's JSON schemas from their npm package.
need_node() {
  if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
    apt_install nodejs npm
  fi
}

# The package itself, at the version tests/foxglove/package-lock.json pins (the test would run
# the same `npm ci` when it is missing; here it is fetched before the clock of any test runs).
need_foxglove_schemas() {
  [ -d tests/foxglove/node_modules/@foxglove/schemas ] ||
    (cd tests/foxglove && npm ci --no-audit --no-fund)
}

# The Python package (python/): a venv in the repository (.venv/, gitignored) with maturin,
# NumPy, pandas, pytest and the package itself, built from this checkout. CARGO_TARGET_DIR:
# maturin builds into the workspace's target/, so the package reuses the compiled crates. The
# e2e tests of Python robots (tests/tests/python_agents.rs) run .venv/bin/python.
PYTHON_PACKAGES=(maturin numpy pandas pytest)
need_python() {
  if ! python3 -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
    apt_install python3
  fi
  if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv 2>/dev/null || { apt_install python3-venv && python3 -m venv .venv; }
  fi
  .venv/bin/pip install -q "${PYTHON_PACKAGES[@]}"
  # --no-build-isolation: the venv's maturin builds it (on PATH for pip's build hooks).
  PATH="$PWD/.venv/bin:$PATH" CARGO_TARGET_DIR="$PWD/target" \
    .venv/bin/pip install -q --no-build-isolation ./python
}

# The runs across hosts (tests/tests/hosts.rs) put each "host" in a network namespace joined
# by veth pairs, made with `ip` (and `tc netem` for scripts/bench-hosts.sh).
need_iproute2() {
  command -v ip >/dev/null && command -v tc >/dev/null || apt_install iproute2
}

NEEDS=(need_rust_tools need_chromium need_tmux need_node need_foxglove_schemas need_python need_iproute2)
for need in "${NEEDS[@]}"; do
  "$need"
done

cargo fmt --all -- --check
cargo clippy --release --workspace --all-targets -- -D warnings
# The e2e tests start the binaries (orchestrator, world, agent) from target/release.
cargo build --release
# The agent program examples (Cargo projects of their own, not workspace members): checked and
# built like the workspace, into its target folder (their .cargo/config.toml says so, and
# CARGO_TARGET_DIR makes sure), reusing its compiled dependencies; tests/tests/own_robots.rs
# runs target/release/rust-boids.
for example in examples/rust-boids; do
  (cd "$example" &&
    cargo fmt -- --check &&
    CARGO_TARGET_DIR="$PWD/../../target" cargo clippy --release -- -D warnings &&
    CARGO_TARGET_DIR="$PWD/../../target" cargo build --release)
done
cargo test --release
# The Python package's tests (real runs of target/release/orchestrator).
.venv/bin/python -m pytest -q python/tests
