"""Fixtures of the package's tests: real runs of the checkout's orchestrator (built by
``cargo build --release``; ``scripts/test.sh`` builds it before pytest runs)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

import swarm

#: The checkout this package lives in (python/tests/ -> the repository).
REPO = Path(__file__).resolve().parents[2]
#: A short run with faults (a SIGKILL, a restart) and radio traffic: every column of a
#: recording has something in it. 8 robots, 200 ticks: under a second.
FAULTY_RUN = ["-n", "8", "--max-ticks", "200", "--chaos-at", "50:3,80:5", "--on-fault", "restart"]


@pytest.fixture(scope="session")
def orchestrator() -> str:
    os.chdir(REPO)
    return swarm.orchestrator()


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def faulty_run(orchestrator, tmp_path_factory) -> Path:
    """A finished run folder (processes executor) with its CSV and events exports beside it."""
    out = tmp_path_factory.mktemp("runs") / "faulty"
    # Exit code 3 (mission not complete in 200 ticks) is a run's end too.
    run = subprocess.run([orchestrator, "up", *FAULTY_RUN, "-o", str(out), "-q"])
    assert run.returncode in swarm.cli.RUN_ENDED
    for fmt in ("csv", "events"):
        subprocess.run([orchestrator, "export", "-f", fmt, str(out)], check=True,
                       capture_output=True)
    return out
