"""The swarm runtime from Python.

- ``swarm.Recording("runs/<id>")``: a finished run's scenario, summary and recording as
  NumPy arrays and pandas DataFrames (decoded by the runtime's own Rust reader).
- ``swarm.up(scenario, **overrides)`` / ``swarm.experiment(file, **overrides)``: the
  orchestrator's command line, run from Python.
- ``swarm.run(Behaviour)``: the entry point of a Python robot program named by a scenario's
  ``[[agents]]`` entry (see ``swarm.agent``).
"""

from .recording import Recording
from .cli import CliError, Experiment, Run, experiment, orchestrator, up

__all__ = ["Recording", "CliError", "Experiment", "Run", "experiment", "orchestrator", "up"]
