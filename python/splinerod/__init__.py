"""splinerod: thin elastic rods (threads, sutures, cables, hair) as B-spline curves
whose control points are the degrees of freedom, with adaptive resolution.

Run a scene::

    import splinerod
    scene = splinerod.bundled_scene("hanging_cable")   # or Scene.from_toml("my.toml")
    sim = scene.simulation()
    sim.run()                       # to the scene's duration
    print(sim.positions([0.25, 0.5, 0.75]))
    result = sim.result()           # the JSON of `splinerod run --json`, as a dict

or build a rod in code (``Material``, ``BSplineSpace``, ``Rod``, ``Pin``, energies,
integrators, ``RodSystem``, ``Simulation``). Bad input raises ``SceneError`` (a
``ValueError``) whose ``field`` names the field; a run that cannot go on raises
``SplinerodError`` (a ``RuntimeError``). ``bundled_scene(name)`` loads one of the
repository's ``scenes/`` (compiled in, so found from any directory) and
``bundled_scenes()`` lists them. ``kernels()`` names the kernel set the
process computes with (``SPLINEROD_KERNELS``; results are bit-identical under one set).

Calibrate: ``fit(scene, observations, params)`` fits scene parameters to observed
markers, points or pin forces and returns a ``FitResult``; a static scene's
``sim.sensitivities(params, s)`` gives the exact derivatives of its equilibrium.
"""

from ._splinerod import (
    Adaptivity,
    Bdf2,
    Bending,
    BSplineSpace,
    Clamp,
    Energy,
    Gravity,
    ImplicitEuler,
    ImplicitMidpoint,
    Integrator,
    Material,
    PeriodicBSplineSpace,
    Pin,
    PointForce,
    PointSpring,
    Rod,
    RodSystem,
    Scene,
    SceneError,
    Simulation,
    SplinerodError,
    StaticSolver,
    Stretching,
    __version__,
    bundled_scene,
    bundled_scenes,
    kernels,
)
from .calibration import FitResult, fit, markers_csv

__all__ = [
    "Adaptivity",
    "Bdf2",
    "Bending",
    "BSplineSpace",
    "Clamp",
    "Energy",
    "FitResult",
    "Gravity",
    "ImplicitEuler",
    "ImplicitMidpoint",
    "Integrator",
    "Material",
    "PeriodicBSplineSpace",
    "Pin",
    "PointForce",
    "PointSpring",
    "Rod",
    "RodSystem",
    "Scene",
    "SceneError",
    "Simulation",
    "SplinerodError",
    "StaticSolver",
    "Stretching",
    "__version__",
    "bundled_scene",
    "bundled_scenes",
    "fit",
    "kernels",
    "markers_csv",
]
