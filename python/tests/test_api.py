"""The simulation API: stepping, callbacks, state and setters, ensembles, threads."""

import pathlib
import sys
import threading

import numpy as np
import pytest
import splinerod

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


def hanging_cable():
    return splinerod.Scene.from_toml(SCENES / "hanging_cable.toml")


def test_step_run_and_time():
    sim = hanging_cable().simulation()
    assert sim.time == 0.0 and sim.steps == 0
    sim.step()
    sim.step(9)
    assert sim.steps == 10
    assert sim.time == pytest.approx(10 * sim.dt)
    made = sim.run(until=0.5)
    assert sim.time == pytest.approx(0.5) and made == round(0.5 / sim.dt) - 10
    before = sim.steps
    assert sim.run() == round(hanging_cable().duration / sim.dt) - before
    assert sim.run() == 0  # at the scene's end


def test_a_callback_that_returns_false_stops_the_run():
    sim = hanging_cable().simulation()
    seen = []

    def watch(s):
        seen.append(s.time)
        return s.steps < 30

    made = sim.run(every=10, callback=watch)
    assert made == 30 and sim.steps == 30 and len(seen) == 3


def test_a_callback_exception_propagates():
    sim = hanging_cable().simulation()

    def fail(s):
        raise KeyError("from the callback")

    with pytest.raises(KeyError):
        sim.run(callback=fail)
    assert sim.steps == 1


def test_text_and_file_and_dict_give_the_same_scene():
    text = (SCENES / "hanging_cable.toml").read_text()
    a, b = splinerod.Scene.from_toml(text).simulation(), hanging_cable().simulation()
    c = splinerod.Scene.from_toml(str(SCENES / "hanging_cable.toml")).simulation()
    for sim in (a, b, c):
        sim.step(50)
    assert np.array_equal(a.control_points, b.control_points)
    assert np.array_equal(b.control_points, c.control_points)


def test_state_arrays():
    sim = hanging_cable().simulation()
    sim.step(100)
    n = sim.control_points.shape[0]
    assert sim.control_points.shape == (n, 3) and sim.velocities.shape == (n, 3)
    assert sim.knots.shape == (n + 4,)
    assert sim.positions([0.0, 0.5, 1.0]).shape == (3, 3)
    assert sim.positions(0.5).shape == (3,)
    assert np.allclose(sim.positions(0.0), [0, 0, 0])
    assert sim.pins.shape == (2, 3)
    energies = sim.energies()
    assert set(energies) >= {"kinetic", "stretch", "gravity"}
    # The cable's weight pulls its pins down once it has settled.
    sim.run()
    assert sim.pin_forces[:, 1].sum() == pytest.approx(-0.1 * 9.81, rel=1e-6)


def test_moving_a_pin_and_setting_velocities():
    sim = hanging_cable().simulation()
    sim.run(until=1.0)
    sim.set_pin(1, [0.6, 0.0, 0.0])
    assert np.array_equal(sim.pins[1], [0.6, 0.0, 0.0])
    sim.run(until=3.0)
    assert np.allclose(sim.positions(1.0), [0.6, 0.0, 0.0], atol=1e-9)
    v = np.zeros_like(sim.velocities)
    v[5:10, 2] = 1.0
    sim.velocities = v
    assert np.array_equal(sim.velocities, v)
    kinetic = sim.energies()["kinetic"]
    assert kinetic > 0.0
    sim.step()
    assert sim.energies()["kinetic"] < kinetic


def ensemble_scene(count):
    text = (SCENES / "ensemble_cables.toml").read_text()
    text = text.replace("count = 1000", f"count = {count}")
    text = text.replace("duration = 2.0", "duration = 0.2")
    return splinerod.Scene.from_toml(text)


def test_ensembles_return_stacked_arrays():
    sim = ensemble_scene(6).simulation()
    assert sim.members == 6
    sim.run()
    s = np.linspace(0.0, 1.0, 5)
    stacked = sim.stacked_positions(s)
    assert stacked.shape == (6, 5, 3)
    for i in range(6):
        assert np.array_equal(stacked[i], sim.positions(s, member=i))
        assert np.array_equal(sim.stacked_control_points()[i], sim.member_control_points(i))
    energies = sim.stacked_energies()
    assert energies["stretch"].shape == (6,)
    assert energies["stretch"][3] == sim.energies(member=3)["stretch"]
    # The members differ (each draws its own parameters) ...
    assert len({round(x, 12) for x in energies["stretch"]}) == 6
    # ... and the result lists each one.
    assert len(sim.result()["ensemble"]) == 6


def test_threads_step_independent_simulations():
    sims = [hanging_cable().simulation() for _ in range(4)]
    threads = [threading.Thread(target=s.run) for s in sims]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    serial = hanging_cable().simulation()
    serial.run()
    for s in sims:
        assert np.array_equal(s.control_points, serial.control_points)


def test_static_scene_runs_once():
    sim = splinerod.Scene.from_toml(SCENES / "catenary_static.toml").simulation()
    assert sim.run() == 1
    assert sim.run() == 0
    assert abs(-sim.positions(0.5)[1] - 0.268663) < 1e-4


def test_code_built_simulation_needs_until_and_has_no_json():
    material = splinerod.Material(1.0, 0.1)
    basis = splinerod.BSplineSpace.clamped_uniform(3, 8, 1.0)
    rod = splinerod.Rod.straight(material, basis, [0, 0, 0], [0.8, 0, 0])
    system = splinerod.RodSystem(rod, [splinerod.Stretching(100.0), splinerod.Gravity()])
    system.add_pin(splinerod.Pin.here(rod, 0.0))
    sim = splinerod.Simulation(system, splinerod.Bdf2(), dt=0.01)
    with pytest.raises(splinerod.SceneError) as caught:
        sim.run()
    assert caught.value.field == "until"
    assert sim.run(until=0.1) == 10
    with pytest.raises(splinerod.SplinerodError):
        sim.to_json()


def test_docstrings_explain():
    for item in (splinerod.Simulation, splinerod.Simulation.run, splinerod.Scene.from_toml):
        assert item.__doc__ and len(item.__doc__) > 20


def test_stepping_releases_the_gil():
    # A Python thread counts while the main thread is inside one step call. Holding the
    # GIL, the call would let it count nothing: the main thread does not give the GIL up
    # between reading the count before the call and after it unless the call releases it.
    sim = hanging_cable().simulation()
    ticks = []
    running = threading.Event()
    done = threading.Event()

    def count():
        running.set()
        while not done.is_set():
            ticks.append(1)

    interval = sys.getswitchinterval()
    counter = threading.Thread(target=count)
    counter.start()
    running.wait()
    try:
        sys.setswitchinterval(0.2)
        before = len(ticks)
        sim.step(1500)
        during = len(ticks) - before
    finally:
        sys.setswitchinterval(interval)
        done.set()
        counter.join()
    assert during > 100, during


def test_code_built_static_solver_runs_once():
    material = splinerod.Material(1.0, 0.1)
    basis = splinerod.BSplineSpace.clamped_uniform(3, 8, 1.0)
    rod = splinerod.Rod.straight(material, basis, [0, 0, 0], [0.8, 0, 0])
    pins = [splinerod.Pin.here(rod, 0.0), splinerod.Pin.here(rod, 1.0)]
    system = splinerod.RodSystem(rod, [splinerod.Stretching(100.0), splinerod.Gravity()], pins)
    sim = splinerod.Simulation(system, splinerod.StaticSolver())
    assert sim.run() == 1
    assert sim.run() == 0
    sim.step()  # an explicit solve is still made
    assert abs(-sim.positions(0.5)[1] - 0.2687) < 1e-3


def test_the_kernel_set_is_named_and_recorded_in_results():
    # SPLINEROD_KERNELS chooses it once per process (scenes/README.md, "Kernel sets").
    assert splinerod.kernels() in ("portable", "avx2-fma")
    sim = hanging_cable().simulation()
    sim.step(3)
    assert sim.result()["kernels"] == splinerod.kernels()


def test_bundled_scenes_are_the_repository_scenes():
    names = splinerod.bundled_scenes()
    assert names == sorted(p.stem for p in SCENES.glob("*.toml"))
    for name in names:
        text = (SCENES / f"{name}.toml").read_text(encoding="utf-8")
        assert splinerod.bundled_scene(name).toml == text, name
    with pytest.raises(splinerod.SceneError, match="hanging_cable") as caught:
        splinerod.bundled_scene("hanging_cabel")
    assert "hanging_cabel" in str(caught.value)
