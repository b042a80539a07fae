"""Reynolds flocking over the radio, as a Python robot program (issue 38's example).

Each tick every robot broadcasts its pose; from the poses it heard (the radio's range, loss and
delay apply) it steers by cohesion (towards their centre), alignment (towards their mean
velocity) and separation (away from those closer than ``separation_radius``), and away from the
obstacle and wall points it senses. Holonomic robots: the command is a velocity (vx, vy),
clamped to the scenario's ``robot.v_max``.

The message (the same bytes as the Rust example's, so the two flock together): four
little-endian float64, ``x, y, vx, vy`` (32 bytes; ``struct "<4d"``).

Run by a scenario's ``[[agents]]`` entry (``boids.toml`` beside this file)::

    orchestrator up -s examples/python-boids/boids.toml
"""

import struct

import numpy as np

import swarm

#: The message: x, y, vx, vy as little-endian float64.
MSG = struct.Struct("<4d")

#: Defaults of the `[agents.params]` table (each a weight per tick, or a distance).
DEFAULTS = {
    # Steering towards the centre of the heard neighbours.
    "cohesion": 0.01,
    # Steering towards their mean velocity.
    "alignment": 0.125,
    # Steering away from neighbours closer than separation_radius.
    "separation": 0.5,
    "separation_radius": 20.0,
    # Steering away from sensed obstacle points closer than avoid_radius.
    "avoid": 1.0,
    "avoid_radius": 15.0,
    # Random jitter (from the runtime's seeded stream), as a fraction of v_max.
    "jitter": 0.05,
}


class Boids:
    def __init__(self, agent: swarm.Agent):
        unknown = set(agent.params) - set(DEFAULTS)
        if unknown:
            raise ValueError(f"agents params: unknown keys {sorted(unknown)}: "
                             f"allowed {sorted(DEFAULTS)}")
        self.p = {**DEFAULTS, **agent.params}
        self.v_max = agent.scenario["robot"]["v_max"]
        self.rng = agent.rng
        self.vel = np.zeros(2)

    def step(self, sense, inbox, out):
        pos = np.array(sense.pos)
        out.broadcast(MSG.pack(pos[0], pos[1], self.vel[0], self.vel[1]))
        p = self.p
        v = self.vel.copy()
        if inbox:
            heard = np.array([MSG.unpack(m.data) for m in inbox if len(m.data) == MSG.size])
            if len(heard):
                others, their_vel = heard[:, :2], heard[:, 2:]
                v += p["cohesion"] * (others.mean(axis=0) - pos)
                v += p["alignment"] * (their_vel.mean(axis=0) - self.vel)
                v += p["separation"] * _away(pos, others, p["separation_radius"])
        obstacles = sense.obstacles
        if len(obstacles):
            v += p["avoid"] * _away(pos, obstacles, p["avoid_radius"])
        v += self.rng.normal(0.0, p["jitter"] * self.v_max, 2)
        speed = np.hypot(v[0], v[1])
        if speed > self.v_max:
            v *= self.v_max / speed
        self.vel = v
        return (float(v[0]), float(v[1]))


def _away(pos, points, radius):
    """The sum of unit vectors from each point closer than `radius`, weighted by closeness."""
    d = pos - points
    dist = np.hypot(d[:, 0], d[:, 1])
    near = (dist < radius) & (dist > 1e-9)
    if not near.any():
        return np.zeros(2)
    w = (radius - dist[near]) / radius / dist[near]
    return (d[near] * w[:, None]).sum(axis=0)


if __name__ == "__main__":
    swarm.run(Boids)
