"""Python robots: a behaviour class run as an agent process of a swarm run.

A behaviour is a class whose constructor takes the :class:`Agent` and whose
``step(sense, inbox, out)`` returns the robot's command for the tick::

    import swarm

    class Still:
        def __init__(self, agent):
            self.rng = agent.rng            # the runtime's seeded stream (NumPy Generator)

        def step(self, sense, inbox, out):
            out.broadcast(sense.pos.tobytes())
            return (0.0, 0.0)               # (vx, vy), or (v, w) for unicycles

    if __name__ == "__main__":
        swarm.run(Still)

and a scenario's ``[[agents]]`` entry names the program (``command = ["python3",
"still.py"]``). ``swarm.run`` hands the behaviour to the runtime's own Rust agent loop
(``swarm::agent``): attach, lock-step barrier, transport, restart and the ack deadline are the
built-in agent's. The GIL is released while the loop waits.

- ``sense``: :class:`swarm.Sense`: ``tick``, ``robot``, ``heading``, ``alive_robots``,
  ``run_state`` and NumPy views of the frame: ``pos``, ``vel`` (2), ``obstacles`` (n x 2),
  ``nearby`` (fields ``robot``, ``pos``, ``vel``), ``entities`` (``id``, ``kind``, ``flags``,
  ``pos``, ``value``). Read-only; a view kept past ``step`` stays as it was. Without NumPy
  (it is imported on first use; 50 agents importing it at once start slower): ``xy``,
  ``vxy`` (tuples) and ``obstacle_list()`` (list of (x, y)).
- ``inbox``: list of :class:`swarm.Message` (``sender``, ``tick``, ``seq``, ``sender_pos``,
  ``unicast``, ``data``: bytes), in (sender, seq) order.
- ``out``: :class:`swarm.Outbox`: ``broadcast(data)``, ``send(robot, data)`` (bytes; False
  past ``radio.max_messages_per_tick``).
- Return ``(a, b)``, :class:`swarm.Command` (``cmd``, ``report``, ``events``) or None (idle).

Determinism: draw only from ``agent.rng`` or ``agent.random`` (seeded from the robot's runtime stream, the same
in every run of the seed). Python's own ``random``, ``numpy.random``'s global state, time or
set/dict orders of objects that hash by id make a run differ from its rerun.

An exception in ``step`` (or a return value that is no command) ends the robot's agent as a
fault: the traceback goes to stderr (the robot's log, ``<run>/logs/robot-<i>.log``), the process
exits with code ``swarm.EXIT_BEHAVIOUR_FAULT`` (5), the world records the robot's death and,
under ``on_fault = "restart"``, a new agent takes the robot over; the run goes on.
"""

from __future__ import annotations

import functools
import json
import signal
import sys
import tomllib
from typing import Any, Callable

from . import _native

Sense = _native.Sense
Message = _native.Message
Outbox = _native.Outbox
Command = _native.Command
EXIT_BEHAVIOUR_FAULT: int = _native.EXIT_BEHAVIOUR_FAULT


class Agent:
    """What a behaviour's constructor gets: this robot and its run.

    Attributes:
        robot: this robot's id; robots: the run's robot count; seed: the run's seed;
        run_id: the run's id; scenario: the resolved scenario (dict); params: this robot's
        ``[[agents]]`` entry's ``params`` table (dict, ``{}`` without one);
        rng: a NumPy Generator seeded from the robot's runtime stream (``Agent::rng(0)`` of
        the Rust SDK), or ``random``: a ``random.Random`` seeded from the same words: the
        only randomness that keeps runs reproducible.
    """

    def __init__(self, info: Any):
        self.robot: int = info.robot
        self.robots: int = info.robots
        self.seed: int = info.seed
        self.run_id: str = info.run_id
        self.scenario: dict = tomllib.loads(info.scenario_toml)
        self.params: dict = json.loads(info.params_json)
        self._rng_words = list(info.rng_words)

    @functools.cached_property
    def random(self) -> "random.Random":
        """A ``random.Random`` seeded from the same runtime stream words as :attr:`rng`: the
        plain-Python seeded stream (no NumPy import, for programs that start fast). A
        generator of its own; Python's global ``random`` is not it."""
        import random

        return random.Random(int.from_bytes(b"".join(w.to_bytes(8, "little")
                                                     for w in self._rng_words), "little"))

    @functools.cached_property
    def rng(self):
        """``numpy.random.Generator(PCG64(SeedSequence(words)))``, ``words`` drawn from the
        robot's runtime stream (NumPy is imported on first use)."""
        import numpy as np

        return np.random.Generator(np.random.PCG64(np.random.SeedSequence(self._rng_words)))

    def __repr__(self) -> str:
        return f"Agent(robot={self.robot} of {self.robots}, seed={self.seed})"


def run(behaviour: Callable[[Agent], Any], argv: list[str] | None = None) -> None:
    """The whole ``__main__`` of a Python robot program: reads the agent arguments
    (``--robot I --prefix P --scenario FILE [--run-id R]``, from ``sys.argv`` unless given),
    builds ``behaviour(agent)`` and runs it until the run ends, then exits with the agent's
    exit code (0 run over, 2 bad input, 3 world gone, 4 setup failed, 5 ``step`` raised)."""
    # Like the Rust agent: Ctrl-C in the terminal ends the process (the orchestrator owns the
    # run's shutdown), not a KeyboardInterrupt inside a step taken for a behaviour fault.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    args = sys.argv[1:] if argv is None else list(argv)
    code = _native.run_agent(args, lambda info: behaviour(Agent(info)))
    sys.stdout.flush()
    sys.stderr.flush()
    sys.exit(code)
