"""A parameter sweep a user would otherwise write a shell loop for: the sag of a hanging
cable against its axial stiffness EA, from a stretchy rope to a nearly inextensible
cable, each point a static solve of the same scene with one value changed.

    python python/examples/sweep.py [--plot sweep.png]

Prints EA, the midpoint sag and the larger pin force, and with matplotlib installed
plots sag against EA.
"""

import argparse
import pathlib

import numpy as np
import splinerod

SCENE = pathlib.Path(__file__).resolve().parents[2] / "scenes" / "catenary_static.toml"


def cable(stiffness):
    """The static catenary scene of SCENE with EA = `stiffness` (N)."""
    return {
        "rod": {
            "rest_length": 1.0,
            "linear_density": 0.1,
            "stretch_stiffness": stiffness,
            "control_points": 16,
            "start": [0.0, 0.0, 0.0],
            "end": [0.8, 0.0, 0.0],
        },
        "pins": [{"at": 0.0}, {"at": 1.0}],
        "world": {"gravity": [0.0, -9.81, 0.0]},
        "solver": {"method": "static"},
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plot", help="write a plot of sag against EA to this file")
    args = parser.parse_args()

    stiffnesses = np.logspace(0, 8, 17)
    sags = []
    print(f"{'EA (N)':>10}  {'sag (m)':>10}  {'pin force (N)':>13}")
    for ea in stiffnesses:
        sim = splinerod.Scene(cable(float(ea))).simulation()
        sim.run()
        sag = -sim.positions(0.5)[1]
        force = np.linalg.norm(sim.pin_forces, axis=1).max()
        sags.append(sag)
        print(f"{ea:10.3g}  {sag:10.6f}  {force:13.6f}")
    inextensible = splinerod.Scene({**cable(1.0), "rod": {**cable(1.0)["rod"], "stretch_stiffness": "inextensible"}})
    sim = inextensible.simulation()
    sim.run()
    print(f"{'inext.':>10}  {-sim.positions(0.5)[1]:10.6f}")

    if args.plot:
        try:
            import matplotlib.pyplot as plt
        except ImportError:
            print("matplotlib is not installed: no plot")
            return
        fig, ax = plt.subplots()
        ax.semilogx(stiffnesses, sags, "o-")
        ax.axhline(-sim.positions(0.5)[1], ls="--", label="inextensible")
        ax.set_xlabel("EA (N)")
        ax.set_ylabel("midpoint sag (m)")
        ax.legend()
        fig.savefig(args.plot, dpi=120)
        print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
