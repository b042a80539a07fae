"""``swarm.Recording``: a run folder read with the runtime's Rust reader (``swarm._native``)."""

from __future__ import annotations

import json
import os
import tomllib

import numpy as np
import pandas as pd

from . import _native


class Recording:
    """A finished run: ``Recording("runs/<id>")`` (the run folder, or its ``recording.bin``).

    Attributes:
        path: the run folder.
        scenario: the resolved scenario (dict, as ``scenario.toml`` / the recording's header).
        summary: ``summary.json`` (dict; ``{}`` when the folder has none).
        seed, version: the recording header's seed and format version.
        ticks: tick numbers (uint64, one per recorded tick).
        poses: float64 array, ticks x robots x 3 (x, y, heading after each tick's actions).
        alive: uint8 array, ticks x robots (1 live, 0 dead).
        states: uint8 array, ticks x robots (each robot's display state).
        events: DataFrame tick, event, robot, entity, detail (as ``orchestrator export
            --format events`` writes them, without time_s).
        radio: DataFrame, a row per tick: the medium's message counters (summary.json's
            ``messages`` fields); ``radio_bytes``: the same in payload bytes.
    """

    def __init__(self, path: str | os.PathLike):
        path = os.fspath(path)
        if os.path.basename(path) == "recording.bin":
            path = os.path.dirname(path) or "."
        self.path = path
        raw = _native.read_recording(os.path.join(path, "recording.bin"))
        self.version: int = raw["version"]
        self.seed: int = raw["seed"]
        self.scenario: dict = tomllib.loads(raw["scenario"])
        summary = os.path.join(path, "summary.json")
        self.summary: dict = {}
        if os.path.exists(summary):
            with open(summary, encoding="utf-8") as f:
                self.summary = json.load(f)
        n = raw["robots"]
        self.ticks = np.frombuffer(raw["ticks"], dtype=np.uint64)
        t = len(self.ticks)
        self.poses = np.frombuffer(raw["poses"], dtype=np.float64).reshape(t, n, 3)
        self.alive = np.frombuffer(raw["alive"], dtype=np.uint8).reshape(t, n)
        self.states = np.frombuffer(raw["states"], dtype=np.uint8).reshape(t, n)
        ev = raw["events"]
        self.events = pd.DataFrame(
            {
                "tick": pd.array(ev["tick"], dtype="UInt64"),
                "event": pd.array(ev["event"], dtype="string"),
                "robot": pd.array(ev["robot"], dtype="UInt32"),
                "entity": pd.array(ev["entity"], dtype="UInt32"),
                "detail": pd.array(ev["detail"], dtype="string"),
            }
        )
        fields = raw["radio_fields"]
        self.radio = self._counters(raw["radio"], fields)
        self.radio_bytes = self._counters(raw["radio_bytes"], fields)

    def _counters(self, data: bytes, fields: list[str]) -> pd.DataFrame:
        rows = np.frombuffer(data, dtype=np.uint64).reshape(len(self.ticks), len(fields))
        df = pd.DataFrame(rows, columns=fields)
        df.insert(0, "tick", self.ticks)
        return df

    @property
    def robots(self) -> int:
        return self.poses.shape[1]

    def __repr__(self) -> str:
        return f"Recording({self.path!r}: {len(self.ticks)} ticks, {self.robots} robots)"
