"""Calibration from Python (issue #48): a static scene's and a run's sensitivities
against central finite differences of two solves or runs (a pin's position too), and the fit of EA and EI of a clamped cable hanging
under gravity from 40 noisy markers (sigma = 0.1 mm)."""

import numpy as np
import pytest

import splinerod

TRUE_EA, TRUE_EI = 50.0, 1e-3
SIGMA = 1e-4
PARAMS = ["rod.stretch_stiffness", "rod.bending_stiffness"]


def cable(ea=TRUE_EA, ei=TRUE_EI, density=0.1):
    """A 1 m cable clamped at s = 0, hanging under its weight (static), as a dict."""
    return {
        "rod": {
            "rest_length": 1.0,
            "linear_density": density,
            "stretch_stiffness": ea,
            "bending_stiffness": ei,
            "control_points": 16,
            "start": [0.0, 0.0, 0.0],
            "end": [1.0, 0.0, 0.0],
        },
        "pins": [{"at": 0.0, "clamp": True}],
        "world": {"gravity": [0.0, -9.81, 0.0]},
        "solver": {"method": "static", "tolerance": 1e-12},
    }


def equilibrium(scene, s):
    """The points at `s` of the scene's equilibrium (one static solve)."""
    sim = splinerod.Scene(scene).simulation()
    sim.run()
    return sim.positions(s)


def markers(seed=48):
    """40 markers of the true cable with sigma = 0.1 mm of noise: rows s, x, y, z, sigma."""
    s = np.arange(1, 41) / 40.0
    points = equilibrium(cable(), s)
    noisy = points + SIGMA * np.random.default_rng(seed).standard_normal(points.shape)
    return np.column_stack([s, noisy, np.full(len(s), SIGMA)])


def test_sensitivities_match_central_differences():
    s = np.linspace(0.05, 1.0, 20)
    params = PARAMS + ["rod.linear_density"]
    sim = splinerod.Scene(cable()).simulation()
    d = sim.sensitivities(params, s)
    assert d.shape == (3, 20, 3)
    keys = ["stretch_stiffness", "bending_stiffness", "linear_density"]
    for k, key in enumerate(keys):
        value = cable()["rod"][key]
        h = 1e-4 * value
        up, down = cable(), cable()
        up["rod"][key] = value + h
        down["rod"][key] = value - h
        fd = (equilibrium(up, s) - equilibrium(down, s)) / (2 * h)
        scale = np.abs(fd).max()
        assert scale > 0, key
        error = np.abs(d[k] - fd).max() / scale
        assert error <= 1e-5, f"{key}: relative error {error:.2e}"


def test_sensitivities_name_an_unknown_parameter():
    sim = splinerod.Scene(cable()).simulation()
    with pytest.raises(ValueError, match="rod.stifness"):
        sim.sensitivities(["rod.stifness"], [0.5])
    with pytest.raises(ValueError, match="s"):
        sim.sensitivities(PARAMS, [1.5])


def swinging(damping=0.3, ei=5e-3, method="implicit-euler"):
    """A cable pinned at s = 0 released horizontally, swinging for 0.5 s, as a dict."""
    scene = cable(ei=ei)
    scene["rod"].update(stretch_stiffness=200.0, damping=damping, control_points=12)
    scene["pins"] = [{"at": 0.0}]
    scene["solver"] = {"method": method, "dt": 0.01, "duration": 0.5, "tolerance": 1e-13}
    return scene


def test_a_runs_sensitivities_match_differences_of_runs():
    params = ["rod.damping", "rod.bending_stiffness"]
    s = np.array([0.25, 0.5, 1.0])
    sim = splinerod.Scene(swinging()).simulation()
    times, history = sim.sensitivity_history(params, s)
    assert history.shape == (len(times), 2, 3, 3)
    assert abs(times[-1] - 0.5) < 1e-9
    end = sim.sensitivities(params, s)
    assert np.array_equal(end, history[-1])
    for k, (key, value) in enumerate([("damping", 0.3), ("bending_stiffness", 5e-3)]):
        h = 1e-4 * value
        up, down = swinging(), swinging()
        up["rod"][key] = value + h
        down["rod"][key] = value - h
        fd = (equilibrium(up, s) - equilibrium(down, s)) / (2 * h)
        error = np.abs(end[k] - fd).max() / np.abs(fd).max()
        assert error <= 1e-5, f"{key}: relative error {error:.2e}"


def test_sensitivities_refuse_a_scheme_without_them():
    scene = swinging(method="implicit-midpoint")
    with pytest.raises(ValueError, match="solver.method"):
        splinerod.Scene(scene).simulation().sensitivities(PARAMS, [0.5])
    with pytest.raises(ValueError, match="solver.method"):
        splinerod.Scene(scene).simulation().sensitivity_history(PARAMS, [0.5])


def test_fit_recovers_ea_and_ei_from_noisy_markers():
    result = splinerod.fit(cable(ea=80.0, ei=2e-3), [markers()], PARAMS)
    assert result.converged
    assert result.names == PARAMS
    assert result.correlation.shape == (2, 2)
    assert not result.warnings
    for name, truth in zip(PARAMS, [TRUE_EA, TRUE_EI]):
        value, std = result.parameters[name], result.std[name]
        assert abs(value / truth - 1) < 0.02, f"{name}: {value} vs {truth}"
        assert abs(value - truth) < 3 * std, f"{name}: {value} ± {std} vs {truth}"
    assert abs(result.residual_rms - 1) < 0.3, result.residual_rms
    assert result.simulations <= 40


def test_fit_reads_csv_files_and_warns_of_what_it_cannot_separate(tmp_path):
    path = tmp_path / "markers.csv"
    path.write_text(splinerod.markers_csv(markers()))
    params = PARAMS + ["rod.linear_density"]
    result = splinerod.fit(cable(ea=80.0, ei=2e-3), [path], ",".join(params))
    assert len(result.warnings) == 1, result.warnings
    assert all(name in result.warnings[0] for name in params)
    ratio = result.parameters["rod.stretch_stiffness"] / result.parameters["rod.linear_density"]
    assert abs(ratio / 500 - 1) < 0.02, ratio


def test_fit_refuses_bad_input():
    with pytest.raises(ValueError, match="rod.stifness"):
        splinerod.fit(cable(), [markers()], ["rod.stifness"])
    with pytest.raises(ValueError, match="shape"):
        splinerod.fit(cable(), [np.zeros((3, 2))], PARAMS)
    with pytest.raises(ValueError, match="observations"):
        splinerod.fit(cable(), [], PARAMS)
    with pytest.raises(OSError):
        splinerod.fit(cable(), ["/nonexistent/markers.csv"], PARAMS)


def test_the_calibration_example_recovers_its_cable(tmp_path):
    import pathlib
    import subprocess
    import sys

    example = pathlib.Path(__file__).resolve().parents[1] / "examples" / "calibrate_cable.py"
    done = subprocess.run(
        [sys.executable, str(example), "--plot", str(tmp_path / "calibration.png")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    fitted = {
        line.split()[0]: float(line.split()[3])
        for line in done.stdout.splitlines()
        if line.startswith("rod.")
    }
    assert abs(fitted["rod.bending_stiffness"] / 0.05 - 1) < 0.02, done.stdout
    assert abs(fitted["rod.stretch_stiffness"] / 40 - 1) < 0.02, done.stdout
    assert "converged: True" in done.stdout


def test_fit_takes_one_array_and_a_scene_object():
    scene = splinerod.Scene(cable(ea=80.0, ei=2e-3))
    result = splinerod.fit(scene, markers(), "rod.stretch_stiffness, rod.bending_stiffness")
    assert result.converged
    assert abs(result.parameters["rod.bending_stiffness"] / TRUE_EI - 1) < 0.02


def catenary(end_x=0.8):
    """A catenary pinned at both ends (static), its second pin driven to (end_x, 0, 0)."""
    scene = cable(ea=100.0)
    del scene["rod"]["bending_stiffness"]
    scene["rod"]["end"] = [0.8, 0.0, 0.0]
    scene["pins"] = [{"at": 0.0}, {"at": 1.0, "path": [[0, 0.8, 0, 0], [1, end_x, 0, 0]]}]
    scene["solver"]["tolerance"] = 1e-13
    return scene


def test_a_pins_position_sensitivities_match_moving_its_path_end():
    # A static solve holds a driven pin at its path's end; the parameter offsets the
    # whole path, so differences of the path's end are its reference.
    s = np.linspace(0.05, 1.0, 20)
    d = splinerod.Scene(catenary()).simulation().sensitivities(["pins[1].position[0]"], s)
    h = 1e-6
    fd = (equilibrium(catenary(0.8 + h), s) - equilibrium(catenary(0.8 - h), s)) / (2 * h)
    error = np.abs(d[0] - fd).max() / np.abs(fd).max()
    assert error <= 1e-5, f"relative error {error:.2e}"
    for bad in ["pins[7].position[0]", "pins[0].position[3]", "rod.degree"]:
        with pytest.raises(ValueError, match=bad.replace("[", r"\[").replace("]", r"\]")):
            splinerod.Scene(catenary()).simulation().sensitivities([bad], s)
