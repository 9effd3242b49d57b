"""Calibrating splinerod to a photographed cable: a 1 m cable clamped at one end hangs
under its own weight; a camera facing its plane photographs 40 taped markers (known
positions along the cable) with half a pixel of noise. From the 2D points alone, the
fit recovers the bending stiffness EI and the axial stiffness EA (the density is known:
the cable was weighed), with their uncertainties.

    python python/examples/calibrate_cable.py [--plot calibration.png]

Prints the true, starting and recovered values with their standard deviations, and
with matplotlib installed plots the markers, the fitted cable and its ±2σ band (the
parameters' covariance carried to the shape by the exact sensitivities).
"""

import argparse

import numpy as np
import splinerod

TRUTH = {"rod.bending_stiffness": 0.05, "rod.stretch_stiffness": 40.0}
START = {"rod.bending_stiffness": 0.1, "rod.stretch_stiffness": 100.0}
PIXEL = 2e-4  # m per pixel in the cable's plane (a calibrated camera)
NOISE = 0.5  # pixels


def cable(values):
    """The static clamped cable with `values` (scene path -> value), as a scene dict."""
    return {
        "rod": {
            "rest_length": 1.0,
            "linear_density": 0.1,
            "stretch_stiffness": values["rod.stretch_stiffness"],
            "bending_stiffness": values["rod.bending_stiffness"],
            "control_points": 16,
            "start": [0.0, 0.0, 0.0],
            "end": [1.0, 0.0, 0.0],
        },
        "pins": [{"at": 0.0, "clamp": True}],
        "world": {"gravity": [0.0, -9.81, 0.0]},
        "solver": {"method": "static", "tolerance": 1e-12},
    }


def photograph(s, seed=1):
    """The markers at `s` of the true cable as a camera sees them: pixel coordinates
    (u, v) of the plane z = 0 with NOISE pixels of noise, back in metres."""
    sim = splinerod.Scene(cable(TRUTH)).simulation()
    sim.run()
    points = sim.positions(s)[:, :2]
    pixels = points / PIXEL + NOISE * np.random.default_rng(seed).standard_normal(points.shape)
    return pixels * PIXEL


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plot", help="write the data, the fit and its ±2σ band to this file")
    args = parser.parse_args()

    s = np.arange(1, 41) / 40.0
    xy = photograph(s)
    sigma = NOISE * PIXEL
    # Markers: s, x, y, z (the photograph's plane), sigma.
    markers = np.column_stack([s, xy, np.zeros(len(s)), np.full(len(s), sigma)])
    params = list(TRUTH)
    result = splinerod.fit(cable(START), [markers], params)

    print(f"{'parameter':<24}{'true':>12}{'start':>12}{'fitted':>14}{'σ':>12}")
    for name in params:
        print(
            f"{name:<24}{TRUTH[name]:12.5g}{START[name]:12.5g}"
            f"{result.parameters[name]:14.6g}{result.std[name]:12.2g}"
        )
    # The z rows are exact (the photograph's plane): about √(2/3) σ for a good fit.
    print(
        f"residual rms {result.residual_rms:.3f} σ, {result.iterations} iterations, "
        f"{result.simulations} simulations, converged: {result.converged}"
    )
    for warning in result.warnings:
        print("warning:", warning)

    # The fitted shape and its uncertainty: Cov(C(s)) = J Σ Jᵀ with J = dC/dp.
    fine = np.linspace(0.0, 1.0, 101)
    sim = splinerod.Scene(cable(result.parameters)).simulation()
    sim.run()
    shape = sim.positions(fine)
    jacobian = sim.sensitivities(params, fine)  # (parameters, points, 3)
    std = np.array([result.std[n] for n in params])
    covariance = result.correlation * np.outer(std, std)
    band = 2 * np.sqrt(np.einsum("ip,ij,jp->p", jacobian[:, :, 1], covariance, jacobian[:, :, 1]))
    print(f"tip at y = {shape[-1, 1]:.5f} m ± {band[-1]:.1e} m (2σ)")

    if args.plot:
        try:
            import matplotlib.pyplot as plt
        except ImportError:
            print('matplotlib is not installed (pip install "./python[plot]"): no plot')
            return
        at = np.interp(s, fine, shape[:, 1])
        fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
        left.plot(shape[:, 0], shape[:, 1], label="fitted cable")
        left.plot(xy[:, 0], xy[:, 1], ".", color="k", ms=4, label="photographed markers")
        left.set_xlabel("x (m)")
        left.set_ylabel("y (m)")
        left.set_aspect("equal")
        left.legend(loc="upper right")
        # The band is far thinner than the cable's sag: shown about the fit, in mm.
        right.fill_between(fine, -1e3 * band, 1e3 * band, alpha=0.3, label="fit ±2σ")
        right.axhline(0.0, lw=1)
        right.plot(s, 1e3 * (xy[:, 1] - at), ".", color="k", ms=4, label="marker − fit")
        right.set_xlabel("s (m of rest length)")
        right.set_ylabel("y about the fit (mm)")
        right.legend()
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
        print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
