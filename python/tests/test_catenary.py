"""The hanging rod against exact solutions: the inextensible catenary (a scene given as a
dict) and the README's cable built in code."""

import math

import numpy as np
import pytest
import splinerod

L, D = 1.0, 0.8  # rest length and pin distance, m


def catenary_parameter():
    """`a` of the catenary of length L between pins D apart: 2a sinh(D/2a) = L."""
    lo, hi = 1e-3, 10.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if 2 * mid * math.sinh(D / (2 * mid)) > L:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def exact_point(a, s):
    """The material point at arclength `s` from the left pin of the inextensible catenary."""
    c = math.sinh(D / (2 * a))
    x = D / 2 + a * math.asinh(s / a - c)
    y = a * math.cosh((x - D / 2) / a) - a * math.cosh(D / (2 * a))
    return np.array([x, y, 0.0])


def inextensible_scene(control_points):
    return splinerod.Scene(
        {
            "rod": {
                "rest_length": L,
                "linear_density": 0.1,
                "stretch_stiffness": "inextensible",
                "control_points": control_points,
                "start": [0.0, 0.0, 0.0],
                "end": [D, 0.0, 0.0],
            },
            "pins": [{"at": 0.0}, {"at": 1.0}],
            "world": {"gravity": [0.0, -9.81, 0.0]},
            "solver": {"method": "static"},
        }
    )


def test_inextensible_catenary_within_a_micrometre():
    sim = inextensible_scene(32).simulation()
    sim.run()
    a = catenary_parameter()
    s = np.linspace(0.0, L, 101)
    got = sim.positions(s)
    exact = np.array([exact_point(a, si) for si in s])
    error = np.abs(got - exact).max()
    assert error < 1e-6, error


def test_inextensible_catenary_tension_profile():
    sim = inextensible_scene(32).simulation()
    sim.run()
    a = catenary_parameter()
    weight = 0.1 * 9.81  # N/m
    s = np.linspace(0.05, 0.95, 19)
    x = np.array([exact_point(a, si)[0] for si in s])
    exact = weight * a * np.cosh((x - D / 2) / a)  # T = H cosh, H = w a
    got = sim.tension(s)
    assert np.abs(got / exact - 1).max() < 1e-4


def test_readme_cable_built_in_code():
    material = splinerod.Material(rest_length=1.0, linear_density=0.1)
    basis = splinerod.BSplineSpace.clamped_uniform(3, 16, 1.0)
    rod = splinerod.Rod.straight(material, basis, [0, 0, 0], [0.8, 0, 0])
    rod.damping = 2.0
    pins = [splinerod.Pin.here(rod, 0.0), splinerod.Pin.here(rod, 1.0)]
    energies = [splinerod.Stretching(100.0), splinerod.Gravity([0, -9.81, 0])]
    system = splinerod.RodSystem(rod, energies=energies, pins=pins)
    sim = splinerod.Simulation(system, splinerod.ImplicitEuler(), dt=0.005)
    sim.step(200)
    sag = -sim.positions(0.5)[1]
    assert 0.2 < sag < 0.35
    # The static solver on the same system: the elastic catenary's midpoint sag.
    statics = splinerod.Simulation(system, splinerod.StaticSolver())
    statics.step()
    assert abs(-statics.positions(0.5)[1] - 0.268663) < 1e-4
    # The weight pulls the pins down (the rod's forces on them).
    assert abs(statics.pin_forces[:, 1].sum() + 0.1 * 9.81) < 1e-9


@pytest.mark.parametrize("formulation", ["mixed", "mixed-consistent", "pointwise"])
def test_formulations_agree_on_the_elastic_catenary(formulation):
    material = splinerod.Material(1.0, 0.1)
    basis = splinerod.BSplineSpace.clamped_uniform(3, 32, 1.0)
    rod = splinerod.Rod.straight(material, basis, [0, 0, 0], [0.8, 0, 0])
    pins = [splinerod.Pin.here(rod, 0.0), splinerod.Pin.here(rod, 1.0)]
    energies = [splinerod.Stretching(100.0, formulation=formulation), splinerod.Gravity()]
    system = splinerod.RodSystem(rod, energies, pins)
    sim = splinerod.Simulation(system, splinerod.StaticSolver())
    sim.run()
    assert abs(-sim.positions(0.5)[1] - 0.268663) < 2e-6


def test_a_cable_built_in_code_takes_the_scenes_default_model():
    """`Stretching(EA)` without a formulation resolves "auto" as a scene does: the cable
    built in code and the bundled scene with the same fields move alike."""
    scene = splinerod.bundled_scene("hanging_cable")
    from_scene = scene.simulation()
    material = splinerod.Material(1.0, 0.1)
    basis = splinerod.BSplineSpace.clamped_uniform(3, 16, 1.0)
    rod = splinerod.Rod.straight(material, basis, [0, 0, 0], [0.8, 0, 0])
    rod.damping = 2.0
    pins = [splinerod.Pin.here(rod, 0.0), splinerod.Pin.here(rod, 1.0)]
    system = splinerod.RodSystem(rod, [splinerod.Stretching(100.0), splinerod.Gravity()], pins)
    in_code = splinerod.Simulation(system, splinerod.ImplicitEuler(), dt=from_scene.dt)
    from_scene.run(until=0.5)
    in_code.run(until=0.5)
    s = np.linspace(0.0, 1.0, 21)
    assert np.abs(in_code.positions(s) - from_scene.positions(s)).max() < 1e-9
    # The lumped form moves differently (that is what the choice decides).
    lumped = splinerod.RodSystem(rod, [splinerod.Stretching(100.0, "mixed"), splinerod.Gravity()], pins)
    other = splinerod.Simulation(lumped, splinerod.ImplicitEuler(), dt=from_scene.dt)
    other.run(until=0.5)
    assert np.abs(other.positions(s) - from_scene.positions(s)).max() > 1e-7
