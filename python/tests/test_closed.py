"""Closed rods from Python: scenes with [rod.ring], rings built in code."""

import math

import numpy as np
import pytest
import splinerod

RING = {
    "rod": {
        "rest_length": 2 * math.pi * 0.1,
        "linear_density": 0.05,
        "stretch_stiffness": 50.0,
        "bending_stiffness": 1e-4,
        "damping": 1.0,
        "control_points": 16,
        "ring": {"radius": 0.1},
    },
    "pins": [{"at": 0.25}],
    "solver": {"method": "implicit-euler", "dt": 0.002, "duration": 0.1},
}


def test_a_ring_scene_reports_its_distinct_control_points():
    sim = splinerod.Scene(RING).simulation()
    sim.run()
    assert sim.control_points.shape == (16, 3)
    assert sim.velocities.shape == (16, 3)
    ends = sim.positions([0.0, RING["rod"]["rest_length"]])
    assert np.linalg.norm(ends[0] - ends[1]) < 1e-12  # no seam: s = 0 and s = L meet
    assert sim.result()["control_points"] == 16


def test_a_ring_built_in_code_rests_and_breathes():
    r0 = 0.2
    material = splinerod.Material(2 * math.pi * r0, 0.1)
    basis = splinerod.PeriodicBSplineSpace.uniform(3, 24, material.rest_length)
    assert (basis.count, basis.degree) == (24, 3)
    rod = splinerod.Rod.ring(material, basis, r0 * 1.001, center=[0, 0, 0], normal=[0, 0, 1])
    assert rod.closed and len(rod) == 24 and rod.control_points.shape == (24, 3)
    system = splinerod.RodSystem(rod, [splinerod.Stretching(10.0, formulation="pointwise")])
    sim = splinerod.Simulation(system, splinerod.ImplicitMidpoint(), dt=2 * math.pi / 50.0 / 400)
    radius = []
    for _ in range(1200):
        sim.step()
        s = np.linspace(0.0, material.rest_length, 41)[:-1]
        radius.append(np.mean(np.linalg.norm(sim.positions(s), axis=1)))
    radius = np.array(radius) - np.mean(radius)
    crossings = np.nonzero((radius[:-1] < 0) & (radius[1:] >= 0))[0]
    period = np.mean(np.diff(crossings)) * sim.dt
    omega = 2 * math.pi / period
    assert omega == pytest.approx(math.sqrt(10.0 / 0.1) / r0, rel=2e-3)


def test_closed_rod_input_is_checked():
    material = splinerod.Material(1.0, 0.1)
    basis = splinerod.PeriodicBSplineSpace.uniform(3, 8, 1.0)
    points = [[math.cos(a), math.sin(a), 0.0] for a in np.linspace(0, 2 * math.pi, 9)[:-1]]
    rod = splinerod.Rod(material, basis, points)
    assert rod.closed and len(rod) == 8
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Rod(material, basis, points[:7])
    assert caught.value.field == "control_points"
    with pytest.raises(splinerod.SceneError):
        splinerod.Rod.ring(material, basis, -0.1)
    with pytest.raises(splinerod.SceneError):
        splinerod.PeriodicBSplineSpace.uniform(3, 3, 1.0)
    bad = dict(RING, rod=dict(RING["rod"], knots="clamped"))
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Scene(bad)
    assert caught.value.field == "rod.knots"
