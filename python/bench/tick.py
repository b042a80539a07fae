"""The Python package's benchmark (BENCHMARKS.md, "Python robots"): runs of real processes
with every robot a Python program (an empty behaviour, the boids example) or the Rust
baseline (an empty behaviour, swarm/examples/empty_agent.rs) at N = 10, 50, 100, and prints
ticks/s, the time per robot-tick and the start-up time (summary.json's figures).

    cargo build --release -p swarm-bins
    cargo build --release -p swarm --example empty_agent
    .venv/bin/python python/bench/tick.py [--robots 10,50,100] [--ticks 500]

Python's own cost per robot-tick = (time per robot-tick, Python) - (same, Rust).
Not a test: the figures depend on the machine and its load.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
ORCHESTRATOR = REPO / "target" / "release" / "orchestrator"
#: The programs compared: name -> the [[agents]] command.
PROGRAMS = {
    "rust-empty": [str(REPO / "target" / "release" / "examples" / "empty_agent")],
    "python-empty": [sys.executable, str(REPO / "python" / "bench" / "empty.py")],
    "python-boids": [sys.executable, str(REPO / "examples" / "python-boids" / "boids.py")],
}
#: The arena and radio of the runs: configs/roam.toml's (a run that lasts its ticks).
BASE = REPO / "configs" / "roam.toml"


def scenario(folder: Path, name: str, robots: int, ticks: int) -> Path:
    base = BASE.read_text()
    body = base.replace('max_ticks = 500', f'max_ticks = {ticks}')
    body += (f'\n[[agents]]\nrobots = "0..{robots}"\ncommand = {json.dumps(PROGRAMS[name])}\n')
    # [[agents]] after the base's [[arena.obstacles]]: an array of tables of its own.
    path = folder / f"{name}-{robots}.toml"
    path.write_text(body.replace("[run]\n", f"[run]\nrobots = {robots}\n", 1))
    return path


def run(folder: Path, sc: Path) -> dict | None:
    """The run's summary.json, or None (the CLI's message printed) if it failed."""
    out = folder / sc.stem
    p = subprocess.run([str(ORCHESTRATOR), "up", "-s", str(sc), "-o", str(out), "-q"],
                       capture_output=True, text=True)
    if p.returncode not in (0, 3):
        print(f"{sc.stem}: exit code {p.returncode}: {p.stderr.strip()}", file=sys.stderr)
        return None
    return json.loads((out / "summary.json").read_text())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robots", default="10,50,100")
    ap.add_argument("--ticks", type=int, default=500)
    a = ap.parse_args()
    sizes = [int(n) for n in a.robots.split(",")]
    print("| program | N | ticks/s (steady) | us per robot-tick | start-up s |")
    print("|---|---|---|---|---|")
    per = {}
    with tempfile.TemporaryDirectory(prefix="swarm-bench-py-") as tmp:
        folder = Path(tmp)
        for n in sizes:
            for name in PROGRAMS:
                s = run(folder, scenario(folder, name, n, a.ticks))
                if s is None:
                    continue
                tps = s["steady_ticks_per_second"]
                us = 1e6 / (tps * n)
                per[(name, n)] = us
                print(f"| {name} | {n} | {tps:,.0f} | {us:.1f} | {s['startup_seconds']:.2f} |",
                      flush=True)
    print()
    for n in sizes:
        if ("python-empty", n) not in per or ("rust-empty", n) not in per:
            continue
        extra = per[("python-empty", n)] - per[("rust-empty", n)]
        print(f"N = {n}: a Python step costs the runtime {extra:.1f} us per robot-tick "
              "beyond a Rust one (empty behaviours)")


if __name__ == "__main__":
    main()
