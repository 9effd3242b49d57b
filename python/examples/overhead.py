"""The cost of calling into splinerod from Python: the 16-point hanging cable stepped
10 000 times one `sim.step()` at a time, against one `sim.step(10000)` call (median of
five runs each, fresh simulations).

    python python/examples/overhead.py
"""

import pathlib
import statistics
import time

import splinerod

SCENE = pathlib.Path(__file__).resolve().parents[2] / "scenes" / "hanging_cable.toml"
STEPS = 10_000


def one_call(scene):
    sim = scene.simulation()
    start = time.perf_counter()
    sim.step(STEPS)
    return time.perf_counter() - start


def many_calls(scene):
    sim = scene.simulation()
    step = sim.step
    start = time.perf_counter()
    for _ in range(STEPS):
        step()
    return time.perf_counter() - start


def main():
    text = SCENE.read_text().replace("duration = 10.0", "duration = 100.0")
    scene = splinerod.Scene.from_toml(text)
    one = statistics.median(one_call(scene) for _ in range(5))
    many = statistics.median(many_calls(scene) for _ in range(5))
    print(f"sim.step({STEPS}):        {one:.4f} s ({one / STEPS * 1e6:.2f} µs per step)")
    print(f"{STEPS} x sim.step():   {many:.4f} s ({many / STEPS * 1e6:.2f} µs per step)")
    print(f"ratio: {many / one:.3f}")


if __name__ == "__main__":
    main()
