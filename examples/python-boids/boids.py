"""Reynolds flocking over the radio, as a Python robot program (issue 38's example).

Each tick every robot broadcasts its pose; from the poses it heard (the radio's range, loss and
delay apply) it steers by cohesion (towards their centre), alignment (towards their mean
velocity) and separation (away from those closer than ``separation_radius``), and away from the
obstacle and wall points it senses. Holonomic robots: the command is a velocity (vx, vy),
clamped to the scenario's ``robot.v_max``.

Plain Python (no NumPy: a few neighbours a tick are faster as floats than as arrays, and 50
robots start faster without importing it); ``agent.random`` is the runtime's seeded stream.

The message: four little-endian float64, ``x, y, vx, vy`` (32 bytes; ``struct "<4d"``). A
Rust robot that hears it uses ``type Msg = Vec<u8>`` and decodes the same four numbers.

Run by a scenario's ``[[agents]]`` entry (``boids.toml`` beside this file)::

    orchestrator up -s examples/python-boids/boids.toml
"""

import math
import struct

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
        self.random = agent.random
        self.vel = (0.0, 0.0)

    def step(self, sense, inbox, out):
        x, y = sense.xy
        vx0, vy0 = self.vel
        out.broadcast(MSG.pack(x, y, vx0, vy0))
        p = self.p
        vx, vy = vx0, vy0
        heard = [MSG.unpack(m.data) for m in inbox if len(m.data) == MSG.size]
        if heard:
            n = len(heard)
            cx = sum(h[0] for h in heard) / n
            cy = sum(h[1] for h in heard) / n
            ax = sum(h[2] for h in heard) / n
            ay = sum(h[3] for h in heard) / n
            sx, sy = _away(x, y, ((h[0], h[1]) for h in heard), p["separation_radius"])
            vx += p["cohesion"] * (cx - x) + p["alignment"] * (ax - vx0) + p["separation"] * sx
            vy += p["cohesion"] * (cy - y) + p["alignment"] * (ay - vy0) + p["separation"] * sy
        ox, oy = _away(x, y, sense.obstacle_list(), p["avoid_radius"])
        vx += p["avoid"] * ox + self.random.gauss(0.0, p["jitter"] * self.v_max)
        vy += p["avoid"] * oy + self.random.gauss(0.0, p["jitter"] * self.v_max)
        speed = math.hypot(vx, vy)
        if speed > self.v_max:
            vx, vy = vx * self.v_max / speed, vy * self.v_max / speed
        self.vel = (vx, vy)
        return (vx, vy)


def _away(x, y, points, radius):
    """The sum of unit vectors from each point closer than `radius`, weighted by closeness."""
    ax = ay = 0.0
    for px, py in points:
        dx, dy = x - px, y - py
        d = math.hypot(dx, dy)
        if 1e-9 < d < radius:
            w = (radius - d) / radius / d
            ax += dx * w
            ay += dy * w
    return ax, ay


if __name__ == "__main__":
    swarm.run(Boids)
