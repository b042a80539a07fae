"""Python behaviours in real runs (the orchestrator spawns them as the [[agents]] programs):
the Sense arrays are views with the frame's values and keep them when kept past a step, the
seeded streams repeat, a behaviour's params arrive. The checks run inside ``step``; a failed
one raises, which ends the robot as a fault that the test then finds in summary.json."""

from __future__ import annotations

import sys
import textwrap

import swarm

#: A behaviour that checks the Sense it gets, keeps last tick's arrays and checks they did
#: not change, and moves by its seeded stream.
CHECKER = textwrap.dedent('''
    import numpy as np
    import swarm

    class Checker:
        def __init__(self, agent):
            assert agent.params == {"gain": 0.5, "name": "x"}, agent.params
            self.agent = agent
            self.kept = None

        def step(self, sense, inbox, out):
            pos = sense.pos
            assert pos.tolist() == list(sense.xy) and not pos.flags.writeable
            assert sense.vel.tolist() == list(sense.vxy)
            obstacles = sense.obstacles
            assert obstacles.shape == (len(sense.obstacle_list()), 2)
            assert [tuple(p) for p in obstacles.tolist()] == sense.obstacle_list()
            nearby = sense.nearby
            assert set(nearby["robot"].tolist()) <= set(range(self.agent.robots))
            assert self.agent.robot not in nearby["robot"].tolist()
            for m in inbox:
                assert m.sender != self.agent.robot
                assert m.data == int(m.sender).to_bytes(4, "little") + m.tick.to_bytes(8, "little")
            if self.kept is not None:
                tick, kept_pos, copy = self.kept
                # A view kept from an earlier tick still holds that tick's values.
                assert kept_pos.tolist() == copy, (tick, kept_pos, copy)
            self.kept = (sense.tick, pos, pos.tolist())
            out.broadcast(self.agent.robot.to_bytes(4, "little") + sense.tick.to_bytes(8, "little"))
            r = self.agent.rng.uniform(-1, 1, 2)
            return swarm.Command(cmd=(float(r[0]), float(r[1])), report=(1.0, 0.0, 0.0, 0.0))

    swarm.run(Checker)
''')


def scenario(tmp_path, script: str) -> str:
    prog = tmp_path / "checker.py"
    prog.write_text(script)
    sc = tmp_path / "sc.toml"
    sc.write_text(textwrap.dedent(f'''
        [run]
        behaviour = "roam"
        robots = 6
        max_ticks = 80
        [robot]
        neighbour_sensing_radius = 200.0
        [[agents]]
        robots = "0..6"
        command = [{sys.executable!r}, {str(prog)!r}]
        [agents.params]
        gain = 0.5
        name = "x"
    '''))
    return str(sc)


def test_sense_views_inbox_params_and_streams_in_a_real_run(orchestrator, tmp_path):
    sc = scenario(tmp_path, CHECKER)
    a = swarm.up(sc, out=str(tmp_path / "a"))
    b = swarm.up(sc, out=str(tmp_path / "b"))
    for run in (a, b):
        s = run.summary
        assert s["faults"] == [], s["faults"]
        assert s["ticks"] == 80
        assert s["messages"]["delivered"] > 0
    ra, rb = a.recording(), b.recording()
    # The robots moved by their seeded streams, the same way in both runs.
    assert (ra.poses[0] != ra.poses[-1]).any()
    assert (ra.poses == rb.poses).all()


def test_a_failed_check_is_a_fault_naming_exit_code_5(orchestrator, tmp_path):
    # The same checker with a check that cannot hold: the test above would see it.
    sc = scenario(tmp_path, CHECKER.replace("assert self.agent.robot not in",
                                            "assert self.agent.robot in"))
    run = swarm.up(sc, out=str(tmp_path / "a"))
    faults = run.summary["faults"]
    assert len(faults) == 6
    assert all("exit code 5" in f["cause"] for f in faults), faults
    log = (tmp_path / "a" / "logs" / "robot-0.log").read_text()
    assert "AssertionError" in log and "Traceback" in log
