"""Calibration: fit a scene's parameters to observations of a real rod (issue #48).

``fit(scene, observations, params)`` runs the least-squares fit of ``splinerod fit``
(Levenberg-Marquardt driven by the exact sensitivities of the equilibrium) and returns
a ``FitResult`` with the fields of its JSON. ``Simulation.sensitivities(params, s)``
gives the derivatives themselves.
"""

import json
import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._splinerod import Scene, SceneError, fit_json

__all__ = ["FitResult", "fit", "markers_csv"]

#: An observation: a CSV file's path, CSV text, a ``(label, csv_text)`` pair, or an
#: array of static markers (rows ``s, x, y, z`` or ``s, x, y, z, sigma``).
Observation = Union[str, "os.PathLike[str]", Tuple[str, str], npt.ArrayLike]


@dataclass(frozen=True)
class FitResult:
    """A fit's result, with the fields of ``splinerod fit --json``.

    ``parameters`` and ``std`` map each scene path to its fitted value and standard
    deviation (from the Gauss-Newton covariance scaled by the residual; infinite for
    parameters the observations cannot separate); ``correlation`` is their correlation
    matrix in the order of ``names``; ``residual_rms`` the root mean square of the
    weighted residuals (in units of the observations' sigma); ``warnings`` one line per
    group of parameters the observations cannot separate (``unidentifiable`` gives the
    groups and the direction they do not see).
    """

    names: List[str]
    parameters: Dict[str, float]
    std: Dict[str, float]
    correlation: npt.NDArray[np.float64]
    residual_rms: float
    iterations: int
    simulations: int
    converged: bool
    warnings: List[str] = field(default_factory=list)
    unidentifiable: List[Dict[str, Any]] = field(default_factory=list)

    @staticmethod
    def from_json(text: str) -> "FitResult":
        """The result of the JSON of ``splinerod fit`` (with ``warnings``)."""
        data = json.loads(text)
        names = [p["name"] for p in data["parameters"]]
        return FitResult(
            names=names,
            parameters={p["name"]: float(p["value"]) for p in data["parameters"]},
            std={p["name"]: _number(p["std"], float("inf")) for p in data["parameters"]},
            correlation=np.array(
                [[_number(c, float("nan")) for c in row] for row in data["correlation"]], dtype=float
            ).reshape(len(names), len(names)),
            residual_rms=float(data["residual_rms"]),
            iterations=int(data["iterations"]),
            simulations=int(data["simulations"]),
            converged=bool(data["converged"]),
            warnings=list(data.get("warnings", [])),
            unidentifiable=list(data.get("unidentifiable", [])),
        )


def _number(value: Any, missing: float) -> float:
    """A JSON number, `missing` for the null JSON writes for an infinite or NaN one."""
    return missing if value is None else float(value)


def markers_csv(markers: npt.ArrayLike) -> str:
    """CSV text of static markers: an ``(n, 4)`` array of rows ``s, x, y, z`` (``s`` in m
    of rest length) or ``(n, 5)`` with a ``sigma`` column (m). ``SceneError`` for
    another shape or a value that is not finite."""
    rows = np.asarray(markers, dtype=float)
    if rows.ndim != 2 or rows.shape[1] not in (4, 5):
        raise SceneError(
            f"markers have shape {rows.shape}: expected (n, 4) rows s, x, y, z or (n, 5) "
            "with sigma"
        )
    if not np.all(np.isfinite(rows)):
        raise SceneError("markers: every value must be a finite number")
    header = "t,s,x,y,z" + (",sigma" if rows.shape[1] == 5 else "")
    lines = [header] + ["," + ",".join(repr(float(v)) for v in row) for row in rows]
    return "\n".join(lines) + "\n"


def _observation(item: Any, index: int) -> Any:
    """An observation as the compiled ``fit_json`` takes it: arrays become CSV text."""
    if isinstance(item, (str, os.PathLike, tuple)):
        return item
    return (f"observations[{index}]", markers_csv(item))


def fit(
    scene: Union[Scene, Dict[str, Any], str, "os.PathLike[str]"],
    observations: Sequence[Observation],
    params: Union[str, Sequence[str]],
) -> FitResult:
    """Fits the parameters ``params`` (scene paths such as ``rod.bending_stiffness``,
    ``rod.stretch_stiffness``, ``rod.linear_density``, ``rod.rest_length``,
    ``pins[0].position[1]``, ``contact.friction``; a list or one comma-separated
    string) of ``scene`` (a
    ``Scene``, a dict, a path or TOML text; static, or an implicit Euler or BDF2 run
    observed at step ends by markers, unlabelled points or pin forces) to
    ``observations``: a list whose entries are observation CSV files (paths), CSV text,
    ``(label, csv_text)`` pairs, or arrays of static markers (see ``markers_csv``). The
    scene's values of the parameters are the starting point. Bad input raises
    ``SceneError`` naming it; an unreadable file ``OSError``."""
    if isinstance(observations, (str, os.PathLike, np.ndarray)):
        observations = [observations]
    given = [_observation(item, i) for i, item in enumerate(observations)]
    return FitResult.from_json(fit_json(scene, given, params))
