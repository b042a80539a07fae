"""``swarm.up`` / ``swarm.experiment``: the real orchestrator run from Python."""

from __future__ import annotations

import pytest

import swarm


def test_up_returns_the_run_folder_and_its_recording(orchestrator, tmp_path):
    run = swarm.up(robots=5, max_ticks=40, seed=3, out=str(tmp_path / "r"))
    assert run.code in swarm.cli.RUN_ENDED
    assert run.path == str(tmp_path / "r")
    rec = run.recording()
    assert rec.poses.shape == (40, 5, 3)
    # The overrides reached the CLI.
    assert rec.summary["seed"] == 3 and rec.scenario["run"]["max_ticks"] == 40


def test_up_with_a_scenario_file(orchestrator, tmp_path):
    run = swarm.up("configs/roam.toml", robots=4, max_ticks=20, out=str(tmp_path / "r"))
    assert run.summary["behaviour"] == "roam" and run.summary["robots"] == 4


def test_up_raises_with_the_clis_message(orchestrator, tmp_path):
    with pytest.raises(swarm.CliError) as err:
        swarm.up(robots=4, loss=7, out=str(tmp_path / "r"))
    assert err.value.code == 2
    assert "loss" in str(err.value)
    with pytest.raises(swarm.CliError, match="bogus"):
        swarm.up(bogus=1, out=str(tmp_path / "r"))


def test_experiment_returns_results_as_a_dataframe(orchestrator, repo, tmp_path):
    exp_file = tmp_path / "exp.toml"
    exp_file.write_text(
        f'scenario = "{repo / "configs" / "search.toml"}"\n'
        'modes = ["BT"]\nrobots = [6]\nseeds = 2\nmax_ticks = 60\n'
    )
    exp = swarm.experiment(exp_file, seeds="4..6", out=str(tmp_path / "e"))
    assert exp.results["seed"].tolist() == [4, 5, 6]
    assert set(exp.results["N"]) == {6}
    assert (exp.results["ticks"] == 60).all()


def test_experiment_raises_on_a_bad_file(orchestrator, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("modes = 3\n")
    with pytest.raises(swarm.CliError, match="bad.toml"):
        swarm.experiment(bad, out=str(tmp_path / "e"))
