"""Bad input raises a Python exception naming the field; a panic surfaces as one; the
state stays as it was."""

import math
import pathlib
import sys

import numpy as np
import pytest
import splinerod

ROOT = pathlib.Path(__file__).resolve().parents[2]


def cable(**rod):
    table = {
        "rod": {
            "rest_length": 1.0,
            "linear_density": 0.1,
            "stretch_stiffness": 100.0,
            "control_points": 16,
            "start": [0.0, 0.0, 0.0],
            "end": [0.8, 0.0, 0.0],
            **rod,
        },
        "pins": [{"at": 0.0}, {"at": 1.0}],
        "world": {"gravity": [0.0, -9.81, 0.0]},
        "solver": {"method": "implicit-euler", "dt": 0.01, "duration": 0.1},
    }
    return table


@pytest.mark.parametrize(
    "change, field",
    [
        ({"rest_length": -1.0}, "rod.rest_length"),
        ({"rest_length": math.nan}, "rod.rest_length"),
        ({"linear_density": math.inf}, "rod.linear_density"),
        ({"rest_length": "long"}, "rod.rest_length"),
        ({"colour": "red"}, "rod.colour"),
        ({"control_points": 2}, "rod.control_points"),
        ({"start": [0.0, math.nan, 0.0]}, "rod.start"),
    ],
)
def test_bad_scene_value_names_the_field(change, field):
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Scene(cable(**change))
    assert caught.value.field == field
    assert field in str(caught.value)
    assert isinstance(caught.value, ValueError)


def test_missing_and_unknown_tables():
    table = cable()
    del table["rod"]["rest_length"]
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Scene(table)
    assert caught.value.field == "rod.rest_length"
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Scene({**cable(), "wrold": {}})
    assert caught.value.field == "wrold"


def scene_error(table):
    """The message of the SceneError `Scene(table)` raises; free of Rust's words and of
    positions in the TOML the dict became."""
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Scene(table)
    message = str(caught.value)
    for rust in ("f64", "usize", "struct ", "invalid type", "line "):
        assert rust not in message, message
    return message


def test_dict_scene_errors_in_the_users_words():
    message = scene_error(cable(rest_length="1.0"))
    assert message == '`rod.rest_length`: expected a number, found the string "1.0"'
    message = scene_error(cable(control_points=16.0))
    assert message == "`rod.control_points`: expected a whole number, found 16.0"
    message = scene_error(cable(start=[0.0, 0.0]))
    assert message == "`rod.start`: expected a list of 3 numbers, found a list of 2"
    message = scene_error({**cable(), "wrold": {"gravity": [0.0, 0.0, 0.0]}})
    assert message == "unknown table [wrold]: did you mean [world]?"
    table = cable(linear_densty=0.1)
    del table["rod"]["linear_density"]
    message = scene_error(table)
    assert "unknown field `rod.linear_densty`: did you mean `linear_density`?" in message


def test_every_missing_field_is_named_at_once():
    table = cable()
    del table["rod"]["linear_density"], table["rod"]["control_points"]
    del table["solver"]["method"]
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Scene(table)
    assert str(caught.value) == (
        "missing fields `rod.linear_density`, `rod.control_points` and `solver.method`"
    )
    assert caught.value.field == "rod.linear_density"
    del table["solver"]
    assert "missing table [solver]" in scene_error(table)


def test_a_path_is_pointed_to_from_toml():
    path = ROOT / "scenes" / "hanging_cable.toml"
    for given in (str(path), path, "[rod]\nrest_length = 1.0\n"):
        with pytest.raises(TypeError, match=r"use Scene\.from_toml\(path_or_text\)"):
            splinerod.Scene(given)
    assert splinerod.Scene.from_toml(path).duration > 0.0


def test_values_toml_has_no_word_for():
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Scene(cable(damping=None))
    assert caught.value.field == "rod.damping"
    with pytest.raises(TypeError):
        splinerod.Scene("not a dict")


def test_numpy_values_are_accepted():
    scene = splinerod.Scene(cable(start=np.zeros(3), control_points=np.int64(12)))
    assert scene.simulation().control_points.shape == (12, 3)


def test_toml_text_errors_keep_line_and_column():
    text = "[rod]\nrest_length = 1.0\nfoo = 2\n"
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Scene.from_toml(text)
    assert caught.value.field == "rod.foo"
    assert "line 3" in str(caught.value)


def test_missing_file_is_an_os_error():
    with pytest.raises(FileNotFoundError):
        splinerod.Scene.from_toml(ROOT / "scenes" / "no_such_scene.toml")


def test_bad_arrays_name_the_argument_and_keep_the_state():
    sim = splinerod.Scene(cable()).simulation()
    sim.step(3)
    before = sim.velocities.copy()
    for bad in (np.zeros((15, 3)), np.zeros((16, 2)), "fast", np.full((16, 3), np.nan)):
        with pytest.raises(splinerod.SceneError) as caught:
            sim.velocities = bad
        assert caught.value.field == "velocities"
    assert np.array_equal(sim.velocities, before)
    with pytest.raises(splinerod.SceneError) as caught:
        sim.positions([0.5, 2.0])
    assert caught.value.field == "s"
    with pytest.raises(splinerod.SceneError) as caught:
        sim.set_pin(5, [0, 0, 0])
    assert caught.value.field == "index"
    with pytest.raises(splinerod.SceneError) as caught:
        sim.set_pin(0, [0, 0])
    assert caught.value.field == "position"
    with pytest.raises(splinerod.SceneError) as caught:
        sim.energies(member=3)
    assert caught.value.field == "member"


def test_wrong_argument_types_raise_type_error():
    sim = splinerod.Scene(cable()).simulation()
    with pytest.raises(TypeError):
        sim.step("ten")
    with pytest.raises((TypeError, OverflowError)):
        sim.step(-1)
    with pytest.raises(splinerod.SceneError) as caught:
        sim.run(every=0)
    assert caught.value.field == "every"


def test_code_built_bad_input():
    material = splinerod.Material(1.0, 0.1)
    basis = splinerod.BSplineSpace.clamped_uniform(3, 8, 1.0)
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Stretching(-5.0)
    assert caught.value.field == "stiffness"
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Stretching(5.0, formulation="stiff")
    assert caught.value.field == "formulation"
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Rod(material, basis, np.zeros((7, 3)))
    assert caught.value.field == "control_points"
    with pytest.raises(splinerod.SceneError):
        splinerod.Rod.straight(splinerod.Material(-1.0, 0.1), basis, [0, 0, 0], [1, 0, 0])
    rod = splinerod.Rod.straight(material, basis, [0, 0, 0], [1, 0, 0])
    with pytest.raises(splinerod.SceneError):
        splinerod.Pin.here(rod, 3.0)
    system = splinerod.RodSystem(rod, [splinerod.Gravity()], [])
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Simulation(system, splinerod.ImplicitEuler())
    assert caught.value.field == "dt"
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.ImplicitEuler(tolerance=-1.0)
    assert caught.value.field == "tolerance"


def test_a_failing_step_raises_and_keeps_the_state():
    # Two Newton iterations, no sub-steps, an unreachable tolerance: a squeezed stiff
    # cable cannot converge in one step.
    table = cable(stretch_stiffness=1e9, end=[0.3, 0.0, 0.0])
    solver = {"dt": 0.5, "duration": 1.0, "newton_iterations": 2, "min_dt": 0.5, "tolerance": 1e-300}
    table["solver"].update(solver)
    sim = splinerod.Scene(table).simulation()
    before = sim.control_points.copy()
    with pytest.raises(splinerod.SplinerodError):
        sim.step()
    assert np.array_equal(sim.control_points, before)
    assert sim.time == 0.0


def test_a_panic_surfaces_as_an_exception_and_poisons_the_object():
    sim = splinerod.Scene(cable()).simulation()
    with pytest.raises(splinerod.SplinerodError, match="internal error"):
        sim._panic_for_tests()
    with pytest.raises(splinerod.SplinerodError, match="unusable"):
        sim.step()


def test_resource_limits_as_in_the_cli():
    table = cable()
    table["solver"].update({"dt": 1e-6, "duration": 100.0})
    scene = splinerod.Scene(table)
    with pytest.raises(splinerod.SceneError) as caught:
        scene.simulation()
    assert "solver" in caught.value.field
    assert "allow_large=True" in str(caught.value)
    assert scene.simulation(allow_large=True).members == 1


def test_dict_values_beyond_toml():
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Scene(cable(control_points=10**30))
    assert caught.value.field == "rod.control_points"
    with pytest.raises(splinerod.SceneError) as caught:
        splinerod.Scene({1: 2})
    assert caught.value.field is None and "keys must be strings" in str(caught.value)


@pytest.mark.skipif(sys.version_info < (3, 11), reason="exception notes are Python 3.11+")
def test_wrong_types_name_the_argument():
    sim = splinerod.Scene(cable()).simulation()
    with pytest.raises(TypeError) as caught:
        sim.step(1.5)
    assert "'n'" in " ".join(getattr(caught.value, "__notes__", []))
