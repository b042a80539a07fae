"""A Python robot that does nothing (stands still, sends nothing): the runtime's own cost of a
Python step, for python/bench/tick.py."""

import swarm


class Empty:
    def __init__(self, agent):
        pass

    def step(self, sense, inbox, out):
        return None


if __name__ == "__main__":
    swarm.run(Empty)
