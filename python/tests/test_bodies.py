"""Rigid bodies from Python: `Simulation.bodies` is the state the JSON's `bodies[i]`
records (bit for bit), and a clamp a body holds cannot be posed by `set_clamp_pose`."""

import numpy as np
import pytest

import splinerod

KEYS = ["position", "orientation", "velocity", "angular_velocity"]


def test_bodies_are_the_json_tracks_last_entries():
    sim = splinerod.bundled_scene("body_pendulum").simulation()
    (start,) = sim.bodies
    assert start["name"] == "bob" and start["mass"] == 2.0
    assert np.array_equal(start["inertia"], 0.01 * np.eye(3))
    assert np.array_equal(start["orientation"], np.zeros(3))
    sim.step(40)
    (bob,) = sim.bodies
    track = sim.result()["bodies"][0]
    assert track["name"] == bob["name"] and track["mass"] == bob["mass"]
    assert len(track["t"]) == 41 and track["t"][-1] == sim.time
    for key in KEYS:
        assert bob[key].shape == (3,) and bob[key].dtype == np.float64
        assert np.array_equal(bob[key], np.array(track[key][-1])), key
    # It swings: 40 steps of 5 ms from rest have moved and turned it.
    assert np.abs(bob["velocity"]).max() > 0.01
    assert np.abs(bob["orientation"][2]) > 1e-4


def test_a_clamp_a_body_holds_cannot_be_posed():
    sim = splinerod.bundled_scene("body_pendulum").simulation()
    sim.step()
    before = sim.control_points.copy()
    with pytest.raises(splinerod.SceneError) as caught:
        sim.set_clamp_pose(1, [0.1, -1.0, 0.0], np.eye(3))
    assert caught.value.field == "pins[1].body", str(caught.value)
    assert "bob" in str(caught.value)
    sim.step()
    # Nothing was moved: the same step as a simulation never asked.
    other = splinerod.bundled_scene("body_pendulum").simulation()
    other.step(2)
    assert np.array_equal(sim.control_points, other.control_points)
    assert not np.array_equal(sim.control_points, before)
