"""Every bundled scene run through Python and through the CLI gives the same JSON, bit
for bit, but the wall-clock fields."""

import json
import subprocess

import pytest
import splinerod

from conftest import SCENES

# Fields that measure the machine, not the simulation.
WALL_CLOCK = {"wall_seconds", "median_step_seconds", "stage_seconds"}


def without_wall_clock(value):
    """`value` (parsed JSON) with every wall-clock field removed, at any depth."""
    if isinstance(value, dict):
        return {k: without_wall_clock(v) for k, v in value.items() if k not in WALL_CLOCK}
    if isinstance(value, list):
        return [without_wall_clock(v) for v in value]
    return value


def cli_result(cli, scene, tmp_path, *extra):
    out = tmp_path / "cli.json"
    subprocess.run(
        [str(cli), "run", str(scene), "--json", str(out), *extra],
        check=True,
        capture_output=True,
    )
    return json.loads(out.read_text())


def test_every_scene_is_bundled():
    assert len(SCENES) >= 20


# The slowest scenes (5-22 s each on 2 cores): CI runs the others (`-m "not slow"`);
# a plain `pytest` runs them all.
SLOW = {"knot_tying_tolerance", "ensemble_cables", "suture_ring", "rope_pileup"}


@pytest.mark.parametrize(
    "scene",
    [pytest.param(s, marks=pytest.mark.slow) if s.stem in SLOW else s for s in SCENES],
    ids=[s.stem for s in SCENES],
)
def test_scene_matches_cli_bit_for_bit(cli, scene, tmp_path):
    expected = cli_result(cli, scene, tmp_path)
    sim = splinerod.Scene.from_toml(scene).simulation()
    sim.run()
    got = sim.result()
    assert without_wall_clock(got) == without_wall_clock(expected)
    # The positions themselves, compared as floats (JSON round-trips f64 exactly).
    assert got["samples"]["positions"] == expected["samples"]["positions"]


def test_stopped_run_matches_cli_max_steps(cli, tmp_path):
    scene = next(s for s in SCENES if s.stem == "grab_adaptive")
    expected = cli_result(cli, scene, tmp_path, "--max-steps", "37")
    sim = splinerod.Scene.from_toml(scene).simulation()
    sim.step(37)
    got = sim.result()
    assert got["interrupted"] is True
    assert without_wall_clock(got) == without_wall_clock(expected)


def test_result_does_not_disturb_the_run(cli, tmp_path):
    scene = next(s for s in SCENES if s.stem == "grab_adaptive")
    expected = cli_result(cli, scene, tmp_path)
    sim = splinerod.Scene.from_toml(scene).simulation()
    for _ in range(5):
        sim.run(until=sim.time + 0.05)
        sim.result()  # a copy is concluded; the run goes on untouched
    sim.run()
    assert without_wall_clock(sim.result()) == without_wall_clock(expected)
