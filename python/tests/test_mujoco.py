"""Co-simulation with MuJoCo (#49, item 3; `python/examples/mujoco_gripper.py`): a free
MuJoCo body holds a splinerod cable's clamp through `set_clamp_pose`, the cable's
wrench acts back through `xfrc_applied`. A heavy bob on a light stiff cable swings with
the physical pendulum's period; the explicit coupling is stable below 2√(M L/EA)."""

import dataclasses
import importlib.util
import math
import pathlib
import subprocess
import sys

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco", reason="mujoco comes from the registry (.ci/run)")

EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "mujoco_gripper.py"
_spec = importlib.util.spec_from_file_location("mujoco_gripper", EXAMPLE)
assert _spec is not None and _spec.loader is not None
example = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(example)


def test_the_mujoco_model_is_the_analytic_pendulums_bob():
    # The analytic periods read the bob from the Pendulum; MuJoCo must have the same one.
    p = example.Pendulum()
    model = mujoco.MjModel.from_xml_string(p.mujoco_xml())
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    bob, clamp = model.body("bob").id, model.site("clamp").id
    assert model.body_mass[bob] == pytest.approx(p.mass, rel=1e-12)
    assert np.allclose(model.body_inertia[bob], p.inertia(), rtol=1e-9)
    assert np.allclose(model.body_iquat[bob], [1, 0, 0, 0])  # principal axes = box axes
    assert np.allclose(data.xipos[bob], p.centre_start(), atol=1e-12)
    turn = np.linalg.norm(p.orientation_start())
    assert np.allclose(data.xmat[bob].reshape(3, 3)[:, 1], [0, 1, 0], atol=1e-12)
    assert math.acos(data.xmat[bob][8]) == pytest.approx(turn, rel=1e-9)
    # The clamp site is the cable's end, at arm() - length before the centre of mass.
    cable_end = p.length * p.direction()
    assert np.allclose(data.site_xpos[clamp], cable_end, atol=1e-12)
    assert p.mass >= 50 * p.linear_density * p.length


def test_a_mujoco_bob_on_a_splinerod_cable_swings_with_the_physical_pendulums_period():
    p = example.Pendulum()  # 10 s at dt = 2 ms: 6.7 periods
    times, angles, _ = example.swing(p)
    assert len(times) == round(p.duration / p.dt)
    measured = example.period(times, angles)
    analytic = p.analytic_period()
    # The bob's inertia and the clamp's moment matter here: the point-mass pendulum's
    # period is 4.7 % shorter, and dropping the moment's shift to the centre of mass
    # (torque about the clamp point applied as is) lengthens the period by 1.1 %.
    assert analytic / (2 * math.pi * math.sqrt(p.arm() / example.GRAVITY)) - 1 > 0.04
    assert abs(measured / analytic - 1) < 0.01, (measured, analytic)
    # Closer: the rigid pendulum with the cable's own 4 g (the rest is the amplitude,
    # θ²/16 = 1.6e-4, and the cable's stretch).
    assert abs(measured / p.rigid_period() - 1) < 5e-4, (measured, p.rigid_period())
    # Small amplitude, no energy drift to speak of.
    last_period = angles[times > times[-1] - measured]
    assert np.abs(last_period).max() == pytest.approx(p.angle, rel=2e-3)



def test_the_mujoco_bob_swings_as_the_same_bob_as_a_native_body():
    # The same pendulum with the bob a splinerod `[[bodies]]` entry welded to the clamp
    # and solved with the cable in one Newton system: the periods agree within 1 %.
    p = dataclasses.replace(example.Pendulum(), duration=4.5)
    times, angles, _ = example.swing(p)
    native_times, native_angles = example.native_swing(p)
    coupled, native = example.period(times, angles), example.period(native_times, native_angles)
    print(f"MuJoCo-held bob {coupled:.6f} s, native body {native:.6f} s")
    assert abs(coupled / native - 1) < 0.01, (coupled, native)
    # Both are the rigid pendulum (with the cable's mass) to a few 1e-4.
    assert abs(native / p.rigid_period() - 1) < 5e-4, (native, p.rigid_period())


def test_the_explicit_coupling_is_stable_below_twice_root_m_over_k():
    p = example.Pendulum(duration=2.0)
    limit = 2.0 * math.sqrt(p.mass * p.length / p.stretch_stiffness)  # k = EA/L
    assert example.bending_limit(p) > 2 * limit  # the axial mode is the fastest here
    assert example.stable(dataclasses.replace(p, dt=0.95 * limit))
    assert not example.stable(dataclasses.replace(p, dt=1.05 * limit))
    heavier = dataclasses.replace(p, mass=4.0)  # twice the limit
    assert example.stable(dataclasses.replace(heavier, dt=1.9 * limit))
    assert not example.stable(dataclasses.replace(heavier, dt=2.1 * limit))


def test_the_example_runs_and_prints_the_comparison():
    done = subprocess.run(
        [sys.executable, str(EXAMPLE), "--duration", "5"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    errors = [
        float(line.split()[-1]) for line in done.stdout.splitlines() if "relative error" in line
    ]
    assert len(errors) == 2, done.stdout
    assert abs(errors[0]) < 0.01, done.stdout


@pytest.mark.slow
def test_a_longer_finer_swing_and_the_measured_stability_limits():
    # 30 s at dt = 0.5 ms (20 periods): the rigid pendulum with the cable's mass and the
    # amplitude's correction θ²/16 within 1.5e-4 (the rest: the cable's stretch).
    p = example.Pendulum(dt=0.0005, duration=30.0)
    times, angles, _ = example.swing(p)
    measured = example.period(times, angles)
    expected = p.rigid_period() * (1 + p.angle**2 / 16)
    assert abs(measured / expected - 1) < 1.5e-4, (measured, expected)
    # The largest stable dt, bisected: 2/ω of the fastest mode of the bob on the cable —
    # the axial one (2√(M L/EA)), or with a stiff cable and a small bob a bending one.
    for kw in [{}, {"mass": 4.0}, {"bending_stiffness": 2000.0, "half_size": (0.05,) * 3}]:
        q = example.Pendulum(**kw)
        axial = 2.0 * math.sqrt(q.mass * q.length / q.stretch_stiffness)
        predicted = min(axial, example.bending_limit(q))
        measured_limit = example.stability_limit(q, guess=predicted)
        assert abs(measured_limit / predicted - 1) < 0.02, (kw, measured_limit, predicted)
