"""6-DOF clamps from Python: `set_clamp_pose` between steps (a rotation matrix or a
quaternion w, x, y, z; the position absolute), `pin_torques`, and refusals."""

import math

import numpy as np
import pytest
import splinerod

# A weightless stiff rod along x clamped at s = 0 (no pose in the scene).
CLAMPED = """
[rod]
rest_length = 1.0
linear_density = 0.01
stretch_stiffness = 1e5
bending_stiffness = 100.0
control_points = 12
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]

[[pins]]
at = 0.0
clamp = true

[[pins]]
at = 0.5
slides_along = [1.0, 0.0, 0.0]

[world]
gravity = [0.0, 0.0, 0.0]

[solver]
method = "implicit-euler"
dt = 0.01
duration = 3.0
"""


def rotation_z(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_a_gripper_turned_by_a_controller_carries_the_rod():
    scene = CLAMPED.replace("[[pins]]\nat = 0.5\nslides_along = [1.0, 0.0, 0.0]\n", "")
    sim = splinerod.Scene.from_toml(scene).simulation()
    # Turn 90° about z in 50 steps of the controller (matrices), moving the clamp
    # point up by 0.2 m; then as a quaternion, the same final pose.
    for k in range(1, 51):
        angle = 0.5 * math.pi * k / 50
        sim.set_clamp_pose(0, [0.0, 0.2 * k / 50, 0.0], rotation_z(angle))
        sim.step()
    half = math.sqrt(0.5)
    sim.set_clamp_pose(0, [0.0, 0.2, 0.0], [half, 0.0, 0.0, half])
    sim.run()
    s = np.linspace(0.0, 1.0, 5)
    expected = np.stack([np.zeros(5), 0.2 + s, np.zeros(5)], axis=1)
    assert np.abs(sim.positions(s) - expected).max() < 1e-9
    # A weightless rod at rest: no wrench on the gripper.
    assert np.abs(sim.pin_forces).max() < 1e-9
    assert sim.pin_torques.shape == (1, 3)
    assert np.abs(sim.pin_torques).max() < 1e-9


def test_bad_clamp_poses_raise_value_errors_naming_them():
    sim = splinerod.Scene.from_toml(CLAMPED).simulation()
    sim.step()
    before = sim.control_points.copy()
    cases = [
        (1, [0, 0, 0], np.eye(3), "index"),  # a plain (sliding) pin
        (7, [0, 0, 0], np.eye(3), "index"),
        (0, [0, 0, math.nan], np.eye(3), "position"),
        (0, [0, 0, 0], 2.0 * np.eye(3), "rotation"),
        (0, [0, 0, 0], np.diag([1.0, 1.0, -1.0]), "rotation"),
        (0, [0, 0, 0], [0.0, 0.0, 0.0, 0.0], "rotation"),
        (0, [0, 0, 0], [1.0, 0.0, math.inf, 0.0], "rotation"),
        (0, [0, 0, 0], [1.0, 0.0, 0.0], "rotation"),
    ]
    for index, position, rotation, field in cases:
        with pytest.raises(ValueError) as caught:
            sim.set_clamp_pose(index, position, rotation)
        assert isinstance(caught.value, splinerod.SceneError)
        assert caught.value.field == field, (index, position, rotation, str(caught.value))
    sim.step()
    # Nothing moved the clamp: the rod is where it was.
    assert np.abs(sim.control_points - before).max() < 1e-12


TWISTED = """
[rod]
rest_length = 0.8
linear_density = 0.05
stretch_stiffness = 1e5
bending_stiffness = 2.0
twist_stiffness = 1.3
control_points = 12
start = [0.0, 0.0, 0.0]
end = [0.8, 0.0, 0.0]

[[pins]]
at = 0.0
clamp = true

[[pins]]
at = 1.0
clamp = true

[world]
gravity = [0.0, 0.0, 0.0]

[solver]
method = "implicit-euler"
dt = 0.02
duration = 1.0
"""


def test_a_controller_rolling_the_gripper_a_full_turn_twists_the_rod():
    sim = splinerod.Scene.from_toml(TWISTED).simulation()
    for k in range(1, 17):
        half = math.pi * k / 16  # a roll of 2πk/16 about x
        sim.set_clamp_pose(1, [0.8, 0.0, 0.0], [math.cos(half), math.sin(half), 0.0, 0.0])
        sim.step()
    sim.run()
    exact = 1.3 * 2.0 * math.pi / 0.8
    twist = sim.result()["twist"]
    assert twist["moment"] == pytest.approx(exact, rel=1e-9)
    # The rod resists the roll: the rolled gripper feels -GJ 2π/L about x.
    assert sim.pin_torques[1][0] == pytest.approx(-exact, rel=1e-9)
    assert sim.pin_torques[0][0] == pytest.approx(exact, rel=1e-9)
