"""``swarm.Recording`` returns the recording's numbers exactly: checked against the
orchestrator's own CSV exports of the same run (``orchestrator export -f csv|events``)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import swarm

POSE = ["x", "y", "heading"]


@pytest.fixture(scope="module")
def rec(faulty_run) -> swarm.Recording:
    return swarm.Recording(faulty_run)


@pytest.fixture(scope="module")
def csv(faulty_run) -> pd.DataFrame:
    # The export writes each float's shortest exact decimal; Python's float() reads it back
    # to the same bits (pandas' own parser need not).
    df = pd.read_csv(faulty_run / "recording.csv", dtype={c: str for c in POSE})
    for c in POSE:
        df[c] = [float(v) for v in df[c]]
    return df


def test_shapes_follow_the_header(rec):
    t, n = len(rec.ticks), rec.summary["robots"]
    assert (t, n) == (200, 8)
    assert rec.poses.shape == (t, n, 3) and rec.poses.dtype == np.float64
    assert rec.alive.shape == (t, n) and rec.states.shape == (t, n)
    assert rec.seed == rec.summary["seed"] == rec.scenario["run"]["seed"]


def test_poses_alive_states_equal_the_csv_export(rec, csv):
    csv = csv.sort_values(["tick", "robot"])
    t, n = rec.poses.shape[:2]
    assert len(csv) == t * n
    assert np.array_equal(csv["tick"].to_numpy().reshape(t, n)[:, 0], rec.ticks)
    for i, col in enumerate(POSE):
        # Exact: the same f64 bits, not approximately.
        assert np.array_equal(csv[col].to_numpy().reshape(t, n), rec.poses[:, :, i])
    assert np.array_equal(csv["alive"].to_numpy().reshape(t, n), rec.alive)
    assert np.array_equal(csv["state"].to_numpy().reshape(t, n), rec.states)
    # The run's faults are in it: robot 3 killed at tick 50.
    assert rec.alive[49, 3] == 1 and rec.alive[51, 3] == 0


def test_events_equal_the_events_export(rec, faulty_run):
    ev = pd.read_csv(faulty_run / "events.csv", keep_default_na=False, dtype=str)
    assert len(rec.events) == len(ev) > 0
    for col in ["tick", "event", "robot", "entity", "detail"]:
        mine = ["" if pd.isna(v) else str(v) for v in rec.events[col]]
        assert mine == ev[col].tolist(), col
    assert "robot_died" in set(rec.events["event"])


def test_radio_counters_add_up_to_the_summary(rec):
    totals = rec.radio.drop(columns=["tick", "in_flight"]).sum()
    want = {k: v for k, v in rec.summary["messages"].items() if k != "in_flight"}
    assert totals.to_dict() == want
    assert rec.radio["in_flight"].iloc[-1] == rec.summary["messages"]["in_flight"]
    byte_totals = rec.radio_bytes.drop(columns=["tick", "in_flight"]).sum().to_dict()
    assert byte_totals == {k: v for k, v in rec.summary["message_bytes"].items()
                           if k != "in_flight"}
    assert want["delivered"] > 0


def test_scenario_is_the_runs_own(rec, faulty_run):
    import tomllib

    with open(faulty_run / "scenario.toml", "rb") as f:
        assert rec.scenario == tomllib.load(f)
    assert rec.scenario["run"]["robots"] == 8


def test_recording_bin_path_also_opens(faulty_run):
    assert swarm.Recording(faulty_run / "recording.bin").path == str(faulty_run)


def test_missing_recording_raises_naming_the_file(tmp_path):
    with pytest.raises(OSError, match="recording.bin"):
        swarm.Recording(tmp_path)
