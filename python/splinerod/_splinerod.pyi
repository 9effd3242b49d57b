"""Type stubs of the compiled module `splinerod._splinerod` (re-exported by `splinerod`)."""

import os
from typing import Any, Callable, Dict, Optional, Sequence, Tuple, Union, final, overload

import numpy as np
import numpy.typing as npt

__version__: str
__all__ = ['Adaptivity', 'SceneError', 'SplinerodError', '__version__', 'Scene', 'Simulation', 'Material', 'BSplineSpace', 'PeriodicBSplineSpace', 'Rod', 'Pin', 'RodSystem', 'Energy', 'Stretching', 'Bending', 'Gravity', 'PointSpring', 'PointForce', 'Clamp', 'Integrator', 'ImplicitEuler', 'ImplicitMidpoint', 'Bdf2', 'StaticSolver', 'kernels', 'bundled_scene', 'bundled_scenes', 'fit_json']

_ArrayLike = npt.ArrayLike
_Points = npt.NDArray[np.float64]

def kernels() -> str:
    """The kernel set this process computes with: "portable" or "avx2-fma"."""

def bundled_scene(name: str) -> "Scene":
    """The bundled scene `name` (a file stem of the repository's scenes/, e.g.
    "hanging_cable"), found wherever the program runs; SceneError lists the names."""

def bundled_scenes() -> list[str]:
    """The names of the bundled scenes, sorted."""

def fit_json(
    scene: Union["Scene", Dict[str, Any], str, "os.PathLike[str]"],
    observations: Sequence[Union[str, "os.PathLike[str]", tuple[str, str]]],
    params: Union[str, Sequence[str]],
) -> str:
    """The JSON of `splinerod fit` (plus `warnings`) for `scene` fitted to
    `observations` (paths, CSV text or (label, csv_text) pairs); `splinerod.fit` wraps
    it into a `FitResult`."""

class SceneError(ValueError):
    """Bad input; `field` names the field (dotted path), `None` if no single one."""

    field: Optional[str]

class SplinerodError(RuntimeError):
    """The simulation could not go on; the state is the one before the failing step."""

@final
class Scene:
    """A validated scene: `Scene.from_toml(path_or_text)` or `Scene(dict)`."""

    def __new__(cls, table: Dict[str, Any]) -> "Scene": ...
    @staticmethod
    def from_toml(source: Union[str, "os.PathLike[str]"]) -> "Scene":
        """A scene from a TOML file, or TOML text (a str with a newline or an '=')."""
    @property
    def toml(self) -> str: ...
    @property
    def duration(self) -> float: ...
    @property
    def members(self) -> int: ...
    def simulation(self, allow_large: bool = False) -> "Simulation": ...

@final
class Simulation:
    """A scene's run (`Scene.simulation()`) or a rod built in code."""

    def __new__(
        cls,
        system: "RodSystem",
        integrator: Optional["Integrator"] = None,
        dt: Optional[float] = None,
        adaptivity: Optional[Adaptivity] = None,
        error_estimate: bool = False,
    ) -> "Simulation": ...
    def step(self, n: int = 1) -> None: ...
    def run(
        self,
        until: Optional[float] = None,
        every: int = 1,
        callback: Optional[Callable[["Simulation"], Optional[bool]]] = None,
    ) -> int: ...
    @property
    def time(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def dt(self) -> float: ...
    @property
    def estimated_error(self) -> Optional[float]: ...
    @property
    def control_point_count(self) -> int: ...
    @property
    def members(self) -> int: ...
    @property
    def control_points(self) -> _Points: ...
    @property
    def velocities(self) -> _Points: ...
    @velocities.setter
    def velocities(self, value: _ArrayLike) -> None: ...
    def set_velocities(self, velocities: _ArrayLike, member: Optional[int] = None) -> None: ...
    @property
    def knots(self) -> _Points: ...
    @property
    def pins(self) -> _Points: ...
    def set_pin(self, index: int, position: _ArrayLike, member: Optional[int] = None) -> None: ...
    def set_clamp_pose(
        self,
        index: int,
        position: _ArrayLike,
        rotation: _ArrayLike,
        member: Optional[int] = None,
    ) -> None:
        """Moves the gripper of clamp `index` from the next step on: the clamp point to
        `position` (absolute, m), the gripper turned by `rotation` against its start (a
        (3, 3) rotation matrix or a quaternion (w, x, y, z)) about the clamp point."""
    @property
    def pin_forces(self) -> _Points: ...
    @property
    def pin_torques(self) -> _Points: ...
    @property
    def bodies(self) -> list[Dict[str, Any]]:
        """Member 0's rigid bodies now: dicts with `name`, `mass` (kg), `inertia`
        ((3, 3), kg m², body frame), `position` (centre of mass, m), `orientation`
        (rotation vector, rad), `velocity` (m/s), `angular_velocity` (rad/s, world
        frame); the arrays as the JSON's `bodies[i]` records them."""
    @overload
    def positions(self, s: float, member: int = 0) -> _Points: ...
    @overload
    def positions(self, s: _ArrayLike, member: int = 0) -> _Points: ...
    def tension(self, s: _ArrayLike, member: int = 0) -> _Points: ...
    def sensitivities(self, params: Union[str, Sequence[str]], s: _ArrayLike) -> _Points:
        """Derivatives (len(params), len(s), 3) of the points at material coordinates `s`
        (m) with respect to the scene paths `params` (stiffnesses, densities, damping,
        rod.rest_length, world.gravity[c], loads[i].force[c], pins[i].position[c],
        contact.friction): a static scene's equilibrium, or the end of an implicit Euler
        or BDF2 run. A point at `s` m stays `s` m along the rod when the rest length
        changes, so its derivative by rod.rest_length includes -(s/L) C'(s)."""
    def sensitivity_history(
        self, params: Union[str, Sequence[str]], s: _ArrayLike
    ) -> Tuple[_Points, _Points]:
        """A run's times (T,) and derivatives (T, len(params), len(s), 3) of its points at
        material coordinates `s` (m), after every step."""
    def energies(self, member: int = 0) -> Dict[str, float]: ...
    def stacked_positions(self, s: _ArrayLike) -> _Points: ...
    def stacked_control_points(self) -> _Points: ...
    def member_control_points(self, member: int) -> _Points: ...
    def stacked_energies(self) -> Dict[str, _Points]: ...
    def to_json(self) -> str: ...
    def result(self) -> Dict[str, Any]: ...

@final
@final
class Adaptivity:
    """Adaptive resolution with the fields of a scene's [adaptivity] table."""

    def __new__(cls, **fields: Any) -> "Adaptivity": ...
    def tolerance_for(self, rest_length: float) -> float: ...

@final
class Material:
    """Rest length (m) and mass per unit rest length (kg/m)."""

    rest_length: float
    linear_density: float
    def __new__(cls, rest_length: float, linear_density: float) -> "Material": ...

@final
class BSplineSpace:
    """A B-spline basis of any degree on [0, rest_length]."""

    def __new__(cls, degree: int, knots: Sequence[float]) -> "BSplineSpace": ...
    @staticmethod
    def clamped_uniform(degree: int, control_points: int, length: float) -> "BSplineSpace": ...
    @property
    def degree(self) -> int: ...
    @property
    def count(self) -> int: ...
    @property
    def knots(self) -> _Points: ...

@final
class PeriodicBSplineSpace:
    """A periodic B-spline basis for closed rods (no seam)."""

    def __new__(cls, degree: int, breaks: Sequence[float], period: float) -> "PeriodicBSplineSpace": ...
    @staticmethod
    def uniform(degree: int, control_points: int, period: float) -> "PeriodicBSplineSpace": ...
    @property
    def degree(self) -> int: ...
    @property
    def count(self) -> int: ...
    @property
    def period(self) -> float: ...
    @property
    def breaks(self) -> _Points: ...

@final
class Rod:
    """A B-spline rod: control points, material, damping."""

    damping: float
    def __new__(
        cls, material: Material, basis: BSplineSpace | PeriodicBSplineSpace, control_points: _ArrayLike
    ) -> "Rod": ...
    @staticmethod
    def straight(material: Material, basis: BSplineSpace, start: _ArrayLike, end: _ArrayLike) -> "Rod": ...
    @staticmethod
    def ring(
        material: Material,
        basis: PeriodicBSplineSpace,
        radius: float,
        center: _ArrayLike | None = None,
        normal: _ArrayLike | None = None,
    ) -> "Rod": ...
    @property
    def closed(self) -> bool: ...
    @property
    def control_points(self) -> _Points: ...
    @property
    def knots(self) -> _Points: ...
    def __len__(self) -> int: ...

@final
class Pin:
    """A material point held at a position (optionally sliding along an axis)."""

    @staticmethod
    def here(rod: Rod, at: float) -> "Pin": ...
    @staticmethod
    def tangent_at(rod: Rod, at: float) -> "Pin": ...
    def sliding(self, axis: _ArrayLike) -> "Pin": ...
    @property
    def at(self) -> float: ...
    @property
    def position(self) -> _Points: ...

class Energy:
    """Base class of the energy terms."""

@final
class Stretching(Energy):
    def __new__(cls, stiffness: float, formulation: str = "auto", rest: str = "arclength") -> "Stretching": ...
    @staticmethod
    def inextensible() -> "Stretching": ...

@final
class Bending(Energy):
    def __new__(cls, stiffness: float) -> "Bending": ...

@final
class Gravity(Energy):
    def __new__(cls, g: Optional[_ArrayLike] = None) -> "Gravity": ...

@final
class PointSpring(Energy):
    def __new__(cls, at: float, target: _ArrayLike, stiffness: float) -> "PointSpring": ...

@final
class PointForce(Energy):
    def __new__(cls, at: float, force: _ArrayLike) -> "PointForce": ...

@final
class Clamp(Energy):
    def __new__(cls, at: float, direction: _ArrayLike, stiffness: float) -> "Clamp": ...

@final
class RodSystem:
    """A rod (copied), its energies and pins."""

    def __new__(cls, rod: Rod, energies: Sequence[Energy] = ..., pins: Sequence[Pin] = ...) -> "RodSystem": ...
    def add_energy(self, energy: Energy) -> None: ...
    def add_pin(self, pin: Pin) -> None: ...

class Integrator:
    """Base class of the integrators."""

@final
class ImplicitEuler(Integrator):
    def __new__(cls, max_iterations: Optional[int] = None, tolerance: Optional[float] = None, line_search: Optional[bool] = None) -> "ImplicitEuler": ...

@final
class ImplicitMidpoint(Integrator):
    def __new__(cls, max_iterations: Optional[int] = None, tolerance: Optional[float] = None, line_search: Optional[bool] = None) -> "ImplicitMidpoint": ...

@final
class Bdf2(Integrator):
    def __new__(cls, max_iterations: Optional[int] = None, tolerance: Optional[float] = None, line_search: Optional[bool] = None) -> "Bdf2": ...

@final
class StaticSolver(Integrator):
    def __new__(cls, max_iterations: Optional[int] = None, tolerance: Optional[float] = None, line_search: Optional[bool] = None) -> "StaticSolver": ...
