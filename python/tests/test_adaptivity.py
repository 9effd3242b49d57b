"""Adaptive resolution for rods built in code: `Adaptivity` with a scene's
`[adaptivity]` fields."""

import numpy as np
import pytest
import splinerod


def hanging_cable(control_points=8, **simulation):
    material = splinerod.Material(1.0, 0.1)
    basis = splinerod.BSplineSpace.clamped_uniform(3, control_points, 1.0)
    rod = splinerod.Rod.straight(material, basis, [0, 0, 0], [0.8, 0, 0])
    rod.damping = 2.0
    pins = [splinerod.Pin.here(rod, 0.0), splinerod.Pin.here(rod, 1.0)]
    system = splinerod.RodSystem(rod, [splinerod.Stretching(100.0), splinerod.Gravity()], pins)
    return splinerod.Simulation(system, splinerod.ImplicitEuler(), dt=0.01, **simulation)


def test_the_tolerance_buys_resolution_and_accuracy():
    reference = hanging_cable(96)
    reference.run(until=3.0)
    s = np.linspace(0.0, 1.0, 41)
    counts, errors = [], []
    for tolerance in (1e-3, 1e-4, 1e-5):
        sim = hanging_cable(adaptivity=splinerod.Adaptivity(tolerance=tolerance))
        sim.run(until=3.0)
        error = np.abs(sim.positions(s) - reference.positions(s)).max()
        assert sim.estimated_error <= 2 * tolerance
        assert error <= 2 * tolerance, (tolerance, error)
        counts.append(sim.control_point_count)
        errors.append(error)
    assert counts[0] > 8 and counts[0] < counts[1] < counts[2]
    assert errors[0] > errors[2]


def test_error_estimate_of_a_fixed_resolution():
    sim = hanging_cable(error_estimate=True)
    assert sim.estimated_error is None
    sim.run(until=1.0)
    assert sim.control_point_count == 8
    assert 1e-5 < sim.estimated_error < 1e-2
    assert hanging_cable().estimated_error is None


def test_disabled_and_curvature_criteria():
    sim = hanging_cable(adaptivity=splinerod.Adaptivity(enabled=False))
    sim.run(until=0.5)
    assert sim.control_point_count == 8
    sim = hanging_cable(adaptivity=splinerod.Adaptivity(insert_threshold=0.02, remove_threshold=0.002))
    sim.run(until=0.5)
    assert sim.control_point_count > 8


@pytest.mark.parametrize(
    "fields, field",
    [
        ({"tolerance": -1.0}, "adaptivity.tolerance"),
        ({"tolerance": float("nan")}, "adaptivity.tolerance"),
        ({"tolerence": 1e-4}, "adaptivity.tolerence"),
        ({"tolerance": 1e-4, "insert_threshold": 0.1}, "adaptivity.insert_threshold"),
        ({"max_control_points": "many"}, "adaptivity.max_control_points"),
    ],
)
def test_bad_fields_name_the_field(fields, field):
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Adaptivity(**fields)
    assert caught.value.field == field


def test_limits_checked_against_the_rod():
    with pytest.raises(splinerod.SceneError) as caught:
        hanging_cable(adaptivity=splinerod.Adaptivity(max_control_points=6))
    assert caught.value.field == "adaptivity.max_control_points"
