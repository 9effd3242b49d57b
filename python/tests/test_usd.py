"""`splinerod run --usd OUT.usda` read back with usd-core (`pxr`): the prims, their
types and attributes, and at every time sample the exact control points against the
run's JSON (probes at every step, samples at the end) within 1e-12 m and against the
Python session's control points; the float `points` are the exact ones rounded once;
a rigid body's Xform at the JSON's `bodies[0]` pose at every sample within 1e-12.
Skipped without `pxr` (CI installs usd-core)."""

import json
import math
import subprocess

import numpy as np
import pytest

pxr = pytest.importorskip("pxr")
from pxr import Gf, Usd, UsdGeom  # noqa: E402

import splinerod  # noqa: E402

EXACT = 1e-12  # m

MULTI = """
[[rods]]
name = "left rope"
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 2.0
control_points = 8
radius = 0.01
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]

[[rods]]
name = "right"
rest_length = 0.6
linear_density = 0.05
stretch_stiffness = 100.0
damping = 2.0
control_points = 7
radius = 0.006
start = [0.0, 0.0, 0.3]
end = [0.6, 0.0, 0.3]

[[pins]]
rod = "left rope"
at = 0.0

[[pins]]
rod = "left rope"
at = 1.0

[[pins]]
rod = "right"
at = 0.0

[[grabs]]
rod = "left rope"
at = 0.3
to = [0.3, -0.2, 0.0]
start_time = 0.0
end_time = 0.1
stiffness = 1000.0

[[cuts]]
rod = "right"
at = 0.5
time = 0.1

[adaptivity]
max_control_points = 64

[contact]
floor = -0.6
friction = 0.3

[[obstacles]]
kind = "sphere"
centre = [0.8, -0.3, 0.3]
radius = 0.05
path = [[0.0, 0.0, 0.0, 0.0], [0.2, 0.0, 0.1, 0.0]]

[[obstacles]]
kind = "capsule"
a = [-0.2, -0.4, -0.2]
b = [0.2, -0.4, 0.6]
radius = 0.02

[[obstacles]]
kind = "plane"
point = [0.0, 0.0, -1.0]
normal = [0.0, 0.0, 1.0]

[solver]
method = "implicit-euler"
dt = 0.005
duration = 0.2

[output]
probes = [{ rod = "left rope", at = 0.3 }, { rod = "left rope", at = 1.0 },
          { rod = "right", at = 0.25 }, { rod = "right", at = 0.75 }]
"""

RING = """
[rod]
rest_length = 0.5026548245743669
linear_density = 0.05
stretch_stiffness = 50.0
bending_stiffness = 2e-4
damping = 0.5
control_points = 12
radius = 0.004

[rod.ring]
radius = 0.08
center = [0.0, 0.15, 0.0]
normal = [0.0, 0.94, 0.342]

[contact]
floor = 0.0

[solver]
method = "implicit-euler"
dt = 0.002
duration = 0.1

[output]
probes = [0.0, 0.1, 0.35, 0.6, 0.9]
"""

CUT_RING = RING + """
[[cuts]]
at = 0.5
time = 0.04

[[cuts]]
at = 0.0
time = 0.06
"""

STATIC_LINEAR = """
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
degree = 1
control_points = 9
start = [0.0, 0.0, 0.0]
end = [0.8, 0.0, 0.0]

[[pins]]
at = 0.0

[[pins]]
at = 1.0

[solver]
method = "static"

[output]
samples = 11
"""


def run(cli, tmp_path, scene, *extra):
    """Runs `scene` (TOML text) with --usd and --json; the stage and the JSON."""
    path = tmp_path / "scene.toml"
    path.write_text(scene)
    usd, out = tmp_path / "out.usda", tmp_path / "out.json"
    args = [str(cli), "run", str(path), "--usd", str(usd), "--json", str(out), *extra]
    subprocess.run(args, check=True, capture_output=True)
    assert not (tmp_path / "out.usda.partial").exists()
    return Usd.Stage.Open(str(usd)), json.loads(out.read_text()), path


def validation_errors(stage):
    """usd-core's validators' findings (none where the module is missing)."""
    try:
        from pxr import UsdValidation
    except ImportError:
        return []
    registry = UsdValidation.ValidationRegistry()
    context = UsdValidation.ValidationContext(registry.GetOrLoadAllValidators())
    return [f"{e.GetName()}: {e.GetMessage()}" for e in context.Validate(stage)]


def de_boor(points, knots, d, u):
    """The B-spline of degree `d` at `u` (in `[t_d, t_n]`)."""
    n = len(points)
    k = int(np.searchsorted(knots, u, side="right")) - 1
    k = min(max(k, d), n - 1)
    p = [np.array(points[j + k - d], dtype=float) for j in range(d + 1)]
    for r in range(1, d + 1):
        for j in range(d, r - 1, -1):
            i = j + k - d
            a = (u - knots[i]) / (knots[i + d - r + 1] - knots[i])
            p[j] = (1.0 - a) * p[j - 1] + a * p[j]
    return p[d]


def exact_curves(prim, t):
    """The exact curves at time code `t`: (control points, knots) each."""
    d = prim.GetAttribute("splinerod:degree").Get()
    counts = list(prim.GetAttribute("splinerod:curveVertexCounts").Get(t))
    points = np.array(prim.GetAttribute("splinerod:controlPoints").Get(t), dtype=float)
    knots = np.array(prim.GetAttribute("splinerod:knots").Get(t), dtype=float)
    assert points.shape == (sum(counts), 3)
    assert len(knots) == sum(n + d + 1 for n in counts)
    curves, p, k = [], 0, 0
    for n in counts:
        curves.append((points[p : p + n], knots[k : k + n + d + 1]))
        p, k = p + n, k + n + d + 1
    return curves


def point_at(prim, t, u, period=None):
    """The exact curve's point at material coordinate `u` (m) at time code `t`; at a
    cut, the piece that starts there (as the simulation evaluates it)."""
    d = prim.GetAttribute("splinerod:degree").Get()
    curves = exact_curves(prim, t)
    for inside in (lambda lo, v, hi: lo <= v < hi, lambda lo, v, hi: lo <= v <= hi):
        for points, knots in curves:
            for v in (u, u + period) if period else (u,):
                if inside(knots[d], v, knots[len(points)]):
                    return de_boor(points, knots, d, v)
    raise AssertionError(f"no curve holds u = {u}")


def check_drawn(prim, t, periodic=False):
    """`points` are the exact control points rounded to float (a periodic curve: all
    but the last d), widths one per point, extent as usd-core computes it; returns the
    largest |float - exact| (m)."""
    curves = UsdGeom.BasisCurves(prim)
    d = prim.GetAttribute("splinerod:degree").Get()
    exact = [c for c, _ in exact_curves(prim, t)]
    drawn = np.concatenate([c[: len(c) - d] if periodic else c for c in exact])
    points = np.array(curves.GetPointsAttr().Get(t), dtype=np.float32)
    assert curves.GetPointsAttr().GetTypeName() == "point3f[]"
    assert list(curves.GetCurveVertexCountsAttr().Get(t)) == [
        len(c) - d if periodic else len(c) for c in exact
    ]
    np.testing.assert_array_equal(points, drawn.astype(np.float32))
    widths = curves.GetWidthsAttr().Get(t)
    assert len(widths) == len(points) and curves.GetWidthsInterpolation() == "vertex"
    expected = UsdGeom.BasisCurves.ComputeExtent(curves.GetPointsAttr().Get(t), widths)
    extent = curves.GetExtentAttr().Get(t)
    np.testing.assert_allclose(np.array(extent), np.array(expected), rtol=0, atol=1e-6)
    return float(np.max(np.abs(points.astype(float) - drawn)))


def local(lengths, k, s):
    """Rod `k`'s own coordinate (m) of fraction `s`, rounded as the simulation has it: the
    rods follow each other in one parameter (their knots are written less the start)."""
    start = sum(lengths[:k])
    end = start + lengths[k]
    joined = start + s * lengths[k]
    if k + 1 < len(lengths) and joined >= end:
        joined = np.nextafter(end, -np.inf)  # the end of a rod another follows
    return joined - start


def probe_differences(stage, result, names, lengths, period=None):
    """Largest distance between every JSON probe and the exact curve at its time code
    (probes are recorded every step, time code = step)."""
    times = stage.GetPrimAtPath("/World").GetAttribute("splinerod:time")
    worst = 0.0
    for probe in result["probes"]:
        k = 0 if probe["rod"] is None else names.index(probe["rod"])
        prim = stage.GetPrimAtPath(f"/World/Rods/{prim_names(names)[k]}")
        for step, (t, x) in enumerate(zip(probe["t"], probe["positions"])):
            assert times.Get(step) == t
            got = point_at(prim, step, local(lengths, k, probe["s"]), period)
            worst = max(worst, float(np.linalg.norm(got - np.array(x))))
    return worst


def prim_names(names):
    return ["".join(c if c.isalnum() else "_" for c in n) or "rod" for n in names]


@pytest.mark.parametrize("degree", [3, 2, 5])
def test_several_rods_adaptive_and_cut_with_obstacles(cli, tmp_path, degree):
    scene = MULTI.replace("\ncontrol_points", f"\ndegree = {degree}\ncontrol_points")
    stage, result, path = run(cli, tmp_path, scene)
    assert validation_errors(stage) == []
    assert UsdGeom.GetStageUpAxis(stage) == "Y"
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == pytest.approx(200.0, rel=1e-12)
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0.0, 40.0)
    assert stage.GetDefaultPrim().GetPath() == "/World"
    names = ["left rope", "right"]
    prims = [stage.GetPrimAtPath(f"/World/Rods/{n}") for n in prim_names(names)]
    lengths = [1.0, 0.6]
    for prim, name in zip(prims, names):
        assert prim.GetTypeName() == "BasisCurves"
        curves = UsdGeom.BasisCurves(prim)
        assert (curves.GetTypeAttr().Get(), curves.GetBasisAttr().Get()) == ("cubic", "bspline")
        assert curves.GetWrapAttr().Get() == "pinned"
        assert prim.GetAttribute("splinerod:name").Get() == name
        assert prim.GetAttribute("splinerod:degree").Get() == degree
        assert curves.GetPointsAttr().GetTimeSamples() == list(range(41))
    # The grabbed rope is refined (its count varies); the cut rod has two curves later.
    counts = [len(UsdGeom.BasisCurves(prims[0]).GetPointsAttr().Get(t)) for t in range(41)]
    assert len(set(counts)) > 1
    assert len(UsdGeom.BasisCurves(prims[1]).GetCurveVertexCountsAttr().Get(0)) == 1
    assert len(UsdGeom.BasisCurves(prims[1]).GetCurveVertexCountsAttr().Get(40)) == 2

    worst_float = max(check_drawn(p, t) for p in prims for t in range(41))
    worst_probe = probe_differences(stage, result, names, lengths)
    assert worst_probe <= EXACT and worst_float < 1e-7
    # The end: every JSON sample of every rod, and its knots.
    for k, (prim, rod) in enumerate(zip(prims, result["rods"])):
        for s, x in zip(rod["samples"]["s"], rod["samples"]["positions"]):
            assert np.linalg.norm(point_at(prim, 40, local(lengths, k, s)) - x) <= EXACT
        # The knots: the JSON's (fractions of the rest length), each cut's d + 1 copies
        # ending one curve and starting the next.
        knots = np.concatenate([t for _, t in exact_curves(prim, 40)])
        cuts = len(exact_curves(prim, 40)) - 1
        assert len(knots) == len(rod["knots"]) + (degree + 1) * cuts
        unique = np.unique(np.round(knots / lengths[k], 14))
        np.testing.assert_allclose(unique, np.unique(np.round(rod["knots"], 14)), atol=1e-14)
    # The Python session's control points at every step: the rods' curves in order.
    sim = splinerod.Scene.from_toml(path).simulation()
    worst_session = 0.0
    for step in range(41):
        exact = np.concatenate([c for p in prims for c, _ in exact_curves(p, step)])
        worst_session = max(worst_session, float(np.max(np.abs(exact - sim.control_points))))
        sim.step()
    assert worst_session <= EXACT
    print(f"\nseveral rods, degree {degree}: probes {worst_probe:.3g} m, "
          f"session {worst_session:.3g} m, float points {worst_float:.3g} m")
    check_obstacles(stage)


def check_obstacles(stage):
    """The floor, the moving sphere, the capsule and the plane where the scene has them."""
    floor = stage.GetPrimAtPath("/World/Obstacles/floor")
    assert floor.GetTypeName() == "Mesh"
    at = UsdGeom.Xformable(floor).ComputeLocalToWorldTransform(0)
    assert at.Transform(Gf.Vec3d(0, 0, 0)) == Gf.Vec3d(0, -0.6, 0)
    sphere = stage.GetPrimAtPath("/World/Obstacles/obstacle_0")
    assert sphere.GetTypeName() == "Sphere" and UsdGeom.Sphere(sphere).GetRadiusAttr().Get() == 0.05
    for code in range(41):
        t = 0.005 * code
        centre = UsdGeom.Xformable(sphere).ComputeLocalToWorldTransform(code).ExtractTranslation()
        assert np.allclose(centre, [0.8, -0.3 + 0.5 * t, 0.3], rtol=0, atol=1e-15)
    capsule = stage.GetPrimAtPath("/World/Obstacles/obstacle_1")
    shape = UsdGeom.Capsule(capsule)
    assert shape.GetAxisAttr().Get() == "Z" and shape.GetRadiusAttr().Get() == 0.02
    h = shape.GetHeightAttr().Get()
    m = UsdGeom.Xformable(capsule).ComputeLocalToWorldTransform(0)
    for z, end in [(-0.5 * h, [-0.2, -0.4, -0.2]), (0.5 * h, [0.2, -0.4, 0.6])]:
        assert np.allclose(m.Transform(Gf.Vec3d(0, 0, z)), end, rtol=0, atol=1e-12)
    plane = stage.GetPrimAtPath("/World/Obstacles/obstacle_2")
    m = UsdGeom.Xformable(plane).ComputeLocalToWorldTransform(0)
    assert np.allclose(m.TransformDir(Gf.Vec3d(0, 1, 0)), [0, 0, 1], atol=1e-15)
    assert np.allclose(m.Transform(Gf.Vec3d(0, 0, 0)), [0, 0, -1], atol=1e-15)


@pytest.mark.parametrize("scene, wrap", [(RING, "periodic"), (CUT_RING, "nonperiodic")])
def test_closed_rod(cli, tmp_path, scene, wrap):
    stage, result, path = run(cli, tmp_path, scene)
    assert validation_errors(stage) == []
    prim = stage.GetPrimAtPath("/World/Rods/rod")
    curves = UsdGeom.BasisCurves(prim)
    assert curves.GetWrapAttr().Get() == wrap and prim.GetAttribute("splinerod:closed").Get()
    codes = curves.GetPointsAttr().GetTimeSamples()
    assert codes == list(range(51))
    worst_float = max(check_drawn(prim, t, periodic=wrap == "periodic") for t in codes)
    length = 0.5026548245743669
    worst = probe_differences(stage, result, [""], [length], period=length)
    assert worst <= EXACT and worst_float < 1e-7
    for s, x in zip(result["samples"]["s"], result["samples"]["positions"]):
        assert np.linalg.norm(point_at(prim, 50, s * length, length) - x) <= EXACT
    if wrap == "periodic":
        sim = splinerod.Scene.from_toml(path).simulation()
        sim.run()
        exact = exact_curves(prim, 50)[0][0]
        assert np.max(np.abs(exact[:12] - sim.control_points)) <= EXACT
    else:
        pieces = [len(curves.GetCurveVertexCountsAttr().Get(t)) for t in (0, 20, 30)]
        assert pieces == [1, 1, 2]  # the first cut opens the loop, the second halves it
    print(f"\n{wrap}: probes {worst:.3g} m, float points {worst_float:.3g} m")


def test_static_degree_one(cli, tmp_path):
    stage, result, _ = run(cli, tmp_path, STATIC_LINEAR)
    assert validation_errors(stage) == []
    assert stage.GetTimeCodesPerSecond() == 1.0 and stage.GetEndTimeCode() == 1.0
    prim = stage.GetPrimAtPath("/World/Rods/rod")
    curves = UsdGeom.BasisCurves(prim)
    assert curves.GetTypeAttr().Get() == "linear" and curves.GetWrapAttr().Get() == "nonperiodic"
    assert curves.GetPointsAttr().GetTimeSamples() == [0.0, 1.0]
    check_drawn(prim, 1)
    for s, x in zip(result["samples"]["s"], result["samples"]["positions"]):
        assert np.linalg.norm(point_at(prim, 1, s * 1.0) - x) <= EXACT
    assert math.isclose(result["time"], prim.GetStage().GetPrimAtPath("/World")
                        .GetAttribute("splinerod:time").Get(1), abs_tol=0)


def test_every_k_records_multiples_and_the_end(cli, tmp_path):
    stage, _, _ = run(cli, tmp_path, RING, "--every", "7")
    codes = UsdGeom.BasisCurves(stage.GetPrimAtPath("/World/Rods/rod")).GetPointsAttr()
    assert codes.GetTimeSamples() == [*range(0, 50, 7), 50]


def test_an_unwritable_path_is_refused_naming_it(cli, tmp_path):
    scene = tmp_path / "ring.toml"
    scene.write_text(RING)
    bad = tmp_path / "missing" / "out.usda"
    done = subprocess.run([str(cli), "run", str(scene), "--usd", str(bad)],
                          capture_output=True, text=True)
    assert done.returncode == 2
    assert "--usd" in done.stderr and str(bad) in done.stderr


POINT3D = """#usda 1.0
(
    defaultPrim = "c"
)
def BasisCurves "c"
{
    uniform token type = "cubic"
    uniform token basis = "bspline"
    int[] curveVertexCounts = [4]
    point3d[] points = [(0, 0, 0), (1, 0.1, 0), (2, 0, 0), (3.0000000000000004, 0, 0)]
}
"""


def test_why_points_are_float(tmp_path):
    """The writer's choice (ARCHITECTURE.md, "USD output"): `point3d[] points` opens and
    reads back its doubles, but it is not the schema's type: usd-core's validation
    reports it and typed reads (extents, bounding boxes) find no points. So `points`
    is `point3f[]` and the doubles go in `splinerod:controlPoints`."""
    path = tmp_path / "p3d.usda"
    path.write_text(POINT3D)
    stage = Usd.Stage.Open(str(path))
    prim = stage.GetPrimAtPath("/c")
    points = UsdGeom.BasisCurves(prim).GetPointsAttr()
    assert points.Get()[3][0] == 3.0000000000000004  # read as doubles, no error
    assert points.GetTypeName() == "point3f[]"  # what the schema says
    assert UsdGeom.Boundable.ComputeExtentFromPlugins(UsdGeom.BasisCurves(prim), 0) is None
    errors = validation_errors(stage)
    if errors:  # usd-core with UsdValidation (24.08 on)
        assert any(e.startswith("AttributeTypeMismatch") for e in errors)


def rotation_vector_quaternion(r):
    """The unit quaternion (w, x, y, z) of the rotation vector `r`."""
    angle = np.linalg.norm(r)
    axis = r / angle if angle > 0 else np.zeros(3)
    return np.array([math.cos(angle / 2), *(math.sin(angle / 2) * axis)])


def test_a_body_is_an_xform_at_its_json_pose(cli, tmp_path):
    scene = splinerod.bundled_scene("body_pendulum").toml
    stage, result, _ = run(cli, tmp_path, scene)
    assert validation_errors(stage) == []
    prim = stage.GetPrimAtPath("/World/Bodies/bob")
    assert prim.IsA(UsdGeom.Xformable) and prim.GetTypeName() == "Xform"
    assert prim.GetAttribute("splinerod:kind").Get() == "body"
    assert prim.GetAttribute("splinerod:name").Get() == "bob"
    assert prim.GetAttribute("splinerod:mass").Get() == 2.0
    assert np.array_equal(np.array(prim.GetAttribute("splinerod:inertia").Get()), 0.01 * np.eye(3))
    track = result["bodies"][0]
    times = stage.GetPrimAtPath("/World").GetAttribute("splinerod:time")
    orient = prim.GetAttribute("xformOp:orient")
    codes = orient.GetTimeSamples()
    assert len(codes) == len(track["t"]) == 861
    moved = turned = 0.0
    for code, t, x, r in zip(codes, track["t"], track["position"], track["orientation"]):
        assert times.Get(code) == t
        m = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(code)
        moved = max(moved, np.abs(np.array(m.ExtractTranslation()) - x).max())
        q = orient.Get(code)
        q = np.array([q.GetReal(), *q.GetImaginary()])
        e = rotation_vector_quaternion(np.array(r))
        turned = max(turned, min(np.abs(q - e).max(), np.abs(q + e).max()))
    assert moved <= EXACT and turned <= EXACT
    shape = stage.GetPrimAtPath("/World/Bodies/bob/shape")
    assert shape.GetTypeName() == "Cube" and UsdGeom.Cube(shape).GetSizeAttr().Get() == 1.0
    # The box of I = 0.01 kg m² about every axis for 2 kg: sides √(6 · 0.01 / 2).
    side = np.array(shape.GetAttribute("xformOp:scale").Get())
    assert np.allclose(side, math.sqrt(0.03), rtol=1e-15, atol=0)
    print(f"\nbody: translate {moved:.3g} m, orient {turned:.3g} from the JSON")


def quaternion_rotate(q, v):
    """`v` turned by the unit quaternion `q` = (w, x, y, z)."""
    w, u = q[0], np.array(q[1:])
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def test_a_bodys_contact_shapes_are_its_children(cli, tmp_path):
    # A capsule (tilted in the body frame) and a sphere on a body dropped on the floor:
    # the children's world frames put the shapes where the JSON's pose puts them.
    scene = splinerod.bundled_scene("body_tow").toml.replace(
        "spheres = [[-0.1, -0.05, -0.1, 0.02], [0.1, -0.05, -0.1, 0.02], "
        "[-0.1, -0.05, 0.1, 0.02], [0.1, -0.05, 0.1, 0.02]]",
        "capsules = [[-0.1, -0.05, -0.1, 0.1, -0.04, 0.1, 0.02]]\n"
        "spheres = [[0.1, -0.05, -0.1, 0.02]]",
    ).replace("duration = 4.0", "duration = 0.5")
    stage, result, _ = run(cli, tmp_path, scene)
    assert validation_errors(stage) == []
    sphere = stage.GetPrimAtPath("/World/Bodies/block/contact_0")
    capsule = stage.GetPrimAtPath("/World/Bodies/block/contact_1")
    assert sphere.GetTypeName() == "Sphere" and capsule.GetTypeName() == "Capsule"
    assert sphere.GetAttribute("splinerod:kind").Get() == "contactSphere"
    assert UsdGeom.Capsule(capsule).GetRadiusAttr().Get() == 0.02
    a, b = np.array([-0.1, -0.05, -0.1]), np.array([0.1, -0.04, 0.1])
    assert abs(UsdGeom.Capsule(capsule).GetHeightAttr().Get() - np.linalg.norm(b - a)) < 1e-15
    track = result["bodies"][0]
    body = stage.GetPrimAtPath("/World/Bodies/block")
    codes = body.GetAttribute("xformOp:orient").GetTimeSamples()
    worst = 0.0
    for code, x, r in zip(codes, track["position"], track["orientation"]):
        q = rotation_vector_quaternion(np.array(r))
        m = UsdGeom.Xformable(capsule).ComputeLocalToWorldTransform(code)
        for end, z in [(a, -1.0), (b, 1.0)]:
            local = np.array(m.Transform(Gf.Vec3d(0.0, 0.0, z * np.linalg.norm(b - a) / 2)))
            worst = max(worst, np.abs(local - (x + quaternion_rotate(q, end))).max())
        m = UsdGeom.Xformable(sphere).ComputeLocalToWorldTransform(code)
        centre = np.array(m.ExtractTranslation())
        expected = x + quaternion_rotate(q, np.array([0.1, -0.05, -0.1]))
        worst = max(worst, np.abs(centre - expected).max())
    print(f"\ncontact shapes: {worst:.3g} m from where the JSON's pose puts them")
    assert worst < 1e-12
