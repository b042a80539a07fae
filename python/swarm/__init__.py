"""The swarm runtime from Python.

- ``swarm.Recording("runs/<id>")``: a finished run's scenario, summary and recording as
  NumPy arrays and pandas DataFrames (decoded by the runtime's own Rust reader).
- ``swarm.up(scenario, **overrides)`` / ``swarm.experiment(file, **overrides)``: the
  orchestrator's command line, run from Python.
- ``swarm.run(Behaviour)``: the entry point of a Python robot program named by a scenario's
  ``[[agents]]`` entry (see ``swarm.agent``).

The run readers (pandas) are imported on first use: a robot program that only needs
``swarm.run`` starts without them (50 agents start at once).
"""

import importlib

from .agent import EXIT_BEHAVIOUR_FAULT, Agent, Command, Message, Outbox, Sense, run

#: Names imported from their module on first use (module, name).
_LAZY = {
    "Recording": "recording",
    "CliError": "cli",
    "Experiment": "cli",
    "Run": "cli",
    "experiment": "cli",
    "orchestrator": "cli",
    "up": "cli",
}

__all__ = [*_LAZY, "Agent", "Command", "Message", "Outbox", "Sense", "run",
           "EXIT_BEHAVIOUR_FAULT"]


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module 'swarm' has no attribute {name!r}")
