"""``swarm.up`` / ``swarm.experiment``: the orchestrator's command line, run from Python.

Which ``orchestrator`` runs (:func:`orchestrator`): ``$SWARM_ORCHESTRATOR`` if set; else
``target/release/orchestrator`` of the checkout that holds the current folder (it or a
parent); else ``orchestrator`` on ``PATH``.
"""

from __future__ import annotations

import datetime
import os
import secrets
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from .recording import Recording

#: The environment variable naming the orchestrator binary to run.
ORCHESTRATOR_ENV = "SWARM_ORCHESTRATOR"
#: Where a checkout's release build puts the binary (relative to the checkout).
CHECKOUT_BINARY = Path("target") / "release" / "orchestrator"
#: Exit codes of a run that ended by itself (README, "Exit codes"): 0 mission accomplished,
#: 3 mission not complete. Any other code raises :class:`CliError`.
RUN_ENDED = (0, 3)


class CliError(RuntimeError):
    """The orchestrator exited with a code other than a run's end; ``str()`` is its message."""

    def __init__(self, args: list[str], code: int, stderr: str):
        self.args_run = args
        self.code = code
        self.stderr = stderr
        super().__init__(f"{' '.join(args)}: exit code {code}\n{stderr.strip()}")


def orchestrator() -> str:
    """The orchestrator binary that :func:`up` and :func:`experiment` run (see the module)."""
    env = os.environ.get(ORCHESTRATOR_ENV)
    if env:
        return env
    here = Path.cwd().resolve()
    for folder in (here, *here.parents):
        candidate = folder / CHECKOUT_BINARY
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return str(candidate)
    found = shutil.which("orchestrator")
    if found:
        return found
    raise FileNotFoundError(
        f"no orchestrator: set ${ORCHESTRATOR_ENV}, build one (cargo build --release -p "
        "orchestrator) in this checkout, or put one on PATH"
    )


def _flags(overrides: dict) -> list[str]:
    """``max_ticks=50`` -> ``--max-ticks 50``; ``True`` -> the bare flag; ``False``/``None``
    -> nothing; a list or tuple -> ``a,b,c``."""
    out: list[str] = []
    for key, value in overrides.items():
        if value is None or value is False:
            continue
        flag = "--" + key.replace("_", "-")
        if value is True:
            out.append(flag)
        elif isinstance(value, (list, tuple)):
            out += [flag, ",".join(str(v) for v in value)]
        else:
            out += [flag, str(value)]
    return out


def _new_folder(parent: str) -> str:
    """A new run folder name as the CLI makes them: runs/<date>-<time>-<4 hex>."""
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    return os.path.join(parent, f"{stamp}-{secrets.token_hex(2)}")


def _run(args: list[str], ok: tuple[int, ...]) -> subprocess.CompletedProcess:
    proc = subprocess.run(args, capture_output=True, text=True)
    if proc.returncode not in ok:
        raise CliError(args, proc.returncode, proc.stderr or proc.stdout)
    return proc


@dataclass
class Run:
    """A run made by :func:`up`: its folder, exit code and printed output."""

    path: str
    code: int
    stdout: str

    @property
    def complete(self) -> bool:
        """The mission was accomplished (exit code 0)."""
        return self.code == 0

    def recording(self) -> Recording:
        return Recording(self.path)

    @property
    def summary(self) -> dict:
        return self.recording().summary


def up(scenario: str | os.PathLike | None = None, *, out: str | None = None, **overrides) -> Run:
    """``orchestrator up -s SCENARIO -o OUT --flag value ...`` (``quiet`` on).

    Overrides are the CLI's own flags with ``_`` for ``-``: ``robots=10, seed=2, max_ticks=100,
    on_fault="restart", executor="processes"``. ``out``: the run folder (default:
    ``runs/<date>-<time>-<hex>``). Returns the :class:`Run` for exit codes 0 and 3 (mission
    accomplished / not complete); raises :class:`CliError` with the CLI's message otherwise.
    """
    args = [orchestrator(), "up"]
    if scenario is not None:
        args += ["-s", os.fspath(scenario)]
    out = out or _new_folder("runs")
    args += ["-o", out, "-q", *_flags(overrides)]
    proc = _run(args, RUN_ENDED)
    return Run(path=out, code=proc.returncode, stdout=proc.stdout)


@dataclass
class Experiment:
    """An experiment's output folder and its ``results.csv`` (one row per run)."""

    path: str
    results: pd.DataFrame
    stdout: str


def experiment(file: str | os.PathLike, *, out: str | None = None, **overrides) -> Experiment:
    """``orchestrator experiment FILE -o OUT --flag value ...`` (``quiet`` on): a sweep whose
    ``results.csv`` comes back as a DataFrame. Overrides as for :func:`up` (``seeds="1..3"``,
    ``runs=2``, ``executor="processes"``). Raises :class:`CliError` on a non-zero exit."""
    out = out or _new_folder(os.path.join("runs", "experiments"))
    args = [orchestrator(), "experiment", os.fspath(file), "-o", out, "-q", *_flags(overrides)]
    proc = _run(args, (0,))
    results = pd.read_csv(os.path.join(out, "results.csv"))
    return Experiment(path=out, results=results, stdout=proc.stdout)
