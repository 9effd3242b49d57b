"""Co-simulation with MuJoCo: a rigid body simulated by MuJoCo holds a splinerod cable's
clamp, and the cable pulls back on the body. The scene is a pendulum: a light, stiff
cable (0.4 m, 4 g) pinned at its top end hangs a heavy bob (a 1 kg box, 250 times the
cable's mass) clamped to its bottom end; the bob is a free body of a MuJoCo model,
gravity acts on it in MuJoCo and on the cable in splinerod. Released 0.05 rad from the
vertical, it swings with the period of the physical pendulum
2π√((I + M l²)/(M g l)) (I about the bob's centre of mass, l from the pivot to it).

    python python/examples/mujoco_gripper.py [--dt 0.002] [--duration 10] [--stability]

Prints the measured period against the analytic one; `--stability` bisects the
largest stable time step and compares it with 2√(M/k), k = EA/L.

The coupling (`ClampCoupling`), once per MuJoCo step, explicit:

1. `mj_step1` computes the body's pose at the step's start (q_n).
2. The rod's clamp is put there: `sim.set_clamp_pose(i, p, G)` with p the clamp site's
   world position (`data.site_xpos`) and G = R_n R_0ᵀ the body's rotation against its
   start (`data.site_xmat`; splinerod's gripper rotation is against the clamp's start,
   about the clamp point). Then `sim.step()` advances the rod by the same dt, ending
   with the clamp at that pose.
3. The rod's wrench goes back: splinerod's `pin_forces[i]` and `pin_torques[i]` are
   what the rod puts on the gripper (torque about the clamp point p), so the body feels
   F = pin_forces[i] at p. MuJoCo's `xfrc_applied[body] = [force, torque]` (world
   frame) acts at the body's centre of mass (`data.xipos`), so the moment is shifted
   there: T = pin_torques[i] + (p - xipos) × F. `mj_step2` then integrates the body
   with it (semi-implicit Euler: v_{n+1} = v_n + dt a(q_n), q_{n+1} from v_{n+1}).

Both simulators use one world frame (z up, SI units, gravity [0, 0, -9.81]); the rod's
time step is MuJoCo's `opt.timestep`. The split `mj_step1`/`mj_step2` needs MuJoCo's
Euler or implicit integrators (not RK4).

Stability limit: the body sees the cable as a spring evaluated at the body's pose at the
step's start — for the body, symplectic Euler on the oscillator body-on-cable, stable
while ω dt < 2 for its fastest mode (the cable is light; the rod itself is implicit and
adds no limit). For a stiff cable that is the axial one, ω² = k/M with k = EA/L, so
dt < 2√(M/k) = 2√(M L/EA). Measured (`--stability`, `stability_limit`: bisection to
0.5 %, stable = the swing and the axial oscillation do not grow): 1.004 × 2√(M L/EA)
= 4.02 ms for M = 1 kg, EA = 1e5 N, L = 0.4 m; 1.004 × for M = 4 kg; 0.996 × for
EA = 4e5 N and for L = 1 m. With a stiff cable and a small bob a bending mode can be the
fastest: EI = 2000 N·m² and a 0.1 m cube gave 0.583 ms, 0.99 × the 2/ω of
`bending_limit` (the cable as a massless pinned-clamped beam). Below the limit the
coupling keeps or damps the axial oscillation the release excites, and the period
hardly depends on dt (-1.9e-4 against the analytic period at 2, 1 and 0.5 ms; +2.2e-4
against the rigid pendulum with the cable's mass, of which 1.6e-4 is the amplitude's
θ²/16).

A mocap body (a robot's gripper moved by its controller) is coupled the same way, steps
1 and 2; `xfrc_applied` does not move a mocap body, so the wrench of step 3 is then a
force-torque sensor's reading.
"""

import argparse
import dataclasses
import math

import mujoco
import numpy as np
import splinerod

GRAVITY = 9.81


@dataclasses.dataclass
class Pendulum:
    """A cable pinned at the origin hanging a box-shaped bob from its lower end; the
    swing starts at rest, `angle` (rad) from the vertical in the x-z plane."""

    length: float = 0.4  # cable, m
    linear_density: float = 0.01  # kg/m
    stretch_stiffness: float = 1e5  # EA, N
    bending_stiffness: float = 50.0  # EI, N·m²
    control_points: int = 8
    mass: float = 1.0  # bob, kg
    half_size: tuple = (0.25, 0.1, 0.1)  # bob's box, m; clamped at its top face's centre
    angle: float = 0.05
    dt: float = 0.002  # s, both simulators
    duration: float = 10.0  # s

    def direction(self):
        """Unit vector from the pivot down the cable at the start."""
        return np.array([math.sin(self.angle), 0.0, -math.cos(self.angle)])

    def arm(self):
        """l: pivot to the bob's centre of mass, m (the cable's stretch neglected)."""
        return self.length + self.half_size[2]

    def inertia(self):
        """Principal moments of the bob about its centre of mass (box axes), kg·m²."""
        a, b, c = (2.0 * h for h in self.half_size)
        m = self.mass / 12.0
        return np.array([m * (b * b + c * c), m * (a * a + c * c), m * (a * a + b * b)])

    def centre_start(self):
        """The bob's centre of mass at the start."""
        return self.arm() * self.direction()

    def orientation_start(self):
        """The bob's rotation vector at the start (about y, its top face to the cable)."""
        return np.array([0.0, -self.angle, 0.0])

    def analytic_period(self):
        """The physical pendulum's small-amplitude period 2π√((I + M l²)/(M g l)), the
        cable massless."""
        i, m, l = self.inertia()[1], self.mass, self.arm()
        return 2.0 * math.pi * math.sqrt((i + m * l * l) / (m * GRAVITY * l))

    def rigid_period(self):
        """The same with the cable's own mass, a rigid uniform rod from the pivot."""
        i, m, l = self.inertia()[1], self.mass, self.arm()
        mc, lc = self.linear_density * self.length, self.length
        inertia = i + m * l * l + mc * lc * lc / 3.0
        return 2.0 * math.pi * math.sqrt(inertia / (GRAVITY * (m * l + mc * lc / 2.0)))

    def cable_scene(self):
        """The splinerod scene of the cable alone: pins[0] the fixed pivot, pins[1] the
        clamp a gripper (the bob) moves."""
        end = self.length * self.direction()
        return {
            "rod": {
                "rest_length": self.length,
                "linear_density": self.linear_density,
                "stretch_stiffness": self.stretch_stiffness,
                "bending_stiffness": self.bending_stiffness,
                "control_points": self.control_points,
                "start": [0.0, 0.0, 0.0],
                "end": [float(end[0]), float(end[1]), float(end[2])],
            },
            "pins": [{"at": 0.0}, {"at": 1.0, "clamp": True}],
            "world": {"gravity": [0.0, 0.0, -GRAVITY]},
            "solver": {"method": "implicit-euler", "dt": self.dt, "duration": self.duration},
        }

    def mujoco_xml(self):
        """The MuJoCo model of the bob alone: a free body `bob` (origin at its centre of
        mass) with a site `clamp` at the cable's end."""
        x, y, z = (float(v) for v in self.centre_start())
        w, qy = math.cos(-self.angle / 2.0), math.sin(-self.angle / 2.0)
        hx, hy, hz = self.half_size
        return f"""<mujoco>
  <option timestep="{self.dt!r}" gravity="0 0 {-GRAVITY!r}" integrator="Euler"/>
  <worldbody>
    <body name="bob" pos="{x!r} {y!r} {z!r}" quat="{w!r} 0 {qy!r} 0">
      <freejoint/>
      <geom type="box" size="{hx!r} {hy!r} {hz!r}" mass="{self.mass!r}"/>
      <site name="clamp" pos="0 0 {hz!r}"/>
    </body>
  </worldbody>
</mujoco>"""


class ClampCoupling:
    """Couples MuJoCo body `body` to clamp `pin` of splinerod simulation `sim`: the
    clamp follows the body's site `site`, the rod's wrench acts on the body (module
    docs). Call `exchange()` between `mj_step1` and `mj_step2`."""

    def __init__(self, model, data, sim, pin, body, site):
        self.model, self.data, self.sim, self.pin = model, data, sim, pin
        self.body = model.body(body).id
        self.site = model.site(site).id
        mujoco.mj_kinematics(model, data)
        self.start = data.site_xmat[self.site].reshape(3, 3).copy()
        self.force = np.zeros(3)  # on the body, N
        self.torque = np.zeros(3)  # on the body about its centre of mass, N·m

    def exchange(self):
        """Moves the clamp to the body's pose, steps the rod, and sets the body's
        `xfrc_applied` to the rod's wrench (force at the centre of mass, moment about it)."""
        data, site = self.data, self.site
        point = data.site_xpos[site].copy()
        rotation = data.site_xmat[site].reshape(3, 3) @ self.start.T
        self.sim.set_clamp_pose(self.pin, point, rotation)
        self.sim.step()
        force = self.sim.pin_forces[self.pin]
        moment = self.sim.pin_torques[self.pin]  # about the clamp point
        self.force = force
        self.torque = moment + np.cross(point - data.xipos[self.body], force)
        data.xfrc_applied[self.body, :3] = self.force
        data.xfrc_applied[self.body, 3:] = self.torque


def swing(p, stop_at=math.pi / 2):
    """Co-simulates pendulum `p` for `p.duration`: the times, the swing angles (of the
    pivot-to-centre-of-mass line from the vertical, rad) and the cable's chord lengths
    (pivot to clamp, m) at the start of every MuJoCo step. Stops early once the angle
    exceeds `stop_at` or the state is not finite (unstable)."""
    model = mujoco.MjModel.from_xml_string(p.mujoco_xml())
    data = mujoco.MjData(model)
    sim = splinerod.Scene(p.cable_scene()).simulation()
    coupling = ClampCoupling(model, data, sim, pin=1, body="bob", site="clamp")
    steps = int(round(p.duration / p.dt))
    times, angles, chords = [], [], []
    for _ in range(steps):
        mujoco.mj_step1(model, data)
        centre = data.xipos[coupling.body]
        times.append(data.time)
        angles.append(math.atan2(centre[0], -centre[2]))
        chords.append(float(np.linalg.norm(data.site_xpos[coupling.site])))
        if not (abs(angles[-1]) < stop_at and np.all(np.isfinite(data.qpos))):
            break
        coupling.exchange()
        mujoco.mj_step2(model, data)
    return np.array(times), np.array(angles), np.array(chords)


def native_swing(p):
    """The same pendulum with the bob as a splinerod rigid body (`[[bodies]]`, welded
    to the cable's clamp, solved in the cable's Newton system): the times and swing
    angles of its recorded centre of mass."""
    scene = p.cable_scene()
    scene["bodies"] = [
        {
            "name": "bob",
            "mass": p.mass,
            "inertia": [float(i) for i in p.inertia()],
            "position": [float(x) for x in p.centre_start()],
            "orientation": [float(x) for x in p.orientation_start()],
        }
    ]
    scene["pins"][1]["body"] = "bob"
    sim = splinerod.Scene(scene).simulation()
    sim.run()
    track = sim.result()["bodies"][0]
    centres = np.array(track["position"])
    return np.array(track["t"]), np.arctan2(centres[:, 0], -centres[:, 2])


def period(times, angles):
    """The mean period of an oscillation about zero: twice the mean spacing of its zero
    crossings (linear interpolation), from the first crossing to the last."""
    s = np.signbit(angles)
    k = np.nonzero(s[1:] != s[:-1])[0]
    crossings = times[k] - angles[k] * (times[k + 1] - times[k]) / (angles[k + 1] - angles[k])
    if len(crossings) < 3:
        raise ValueError(f"{len(crossings)} zero crossings: no period")
    return 2.0 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)


def stable(p, window=0.25):
    """Whether pendulum `p` swings stably: it runs to its end, its swing stays within
    10 % of the release angle, and the chord's oscillation (the axial mode the release
    excites) has not doubled from the first `window` seconds to the last (an unstable
    mode grows exponentially: near the limit, ω dt = 2(1 + ε), by about 1 + 2√ε a step;
    a stable one is kept or damped)."""
    times, angles, chords = swing(p)
    n = int(round(window / p.dt))
    if len(times) < int(round(p.duration / p.dt)) or len(times) < 2 * n:
        return False
    if np.abs(angles).max() > 1.1 * p.angle:
        return False
    return bool(np.ptp(chords[-n:]) < 2.0 * np.ptp(chords[:n]))


def stability_limit(p, guess=None, duration=2.0, rel=0.005):
    """The largest stable dt of pendulum `p`, s: bisection to `rel` within half and one
    and a half times `guess` (default the axial limit 2√(M L/EA))."""
    if guess is None:
        guess = 2.0 * math.sqrt(p.mass * p.length / p.stretch_stiffness)
    low, high = 0.5 * guess, 1.5 * guess

    def check(dt):
        return stable(dataclasses.replace(p, dt=dt, duration=duration))

    if not check(low) or check(high):
        raise RuntimeError(f"the limit is not within [{low}, {high}]")
    while high - low > rel * low:
        middle = 0.5 * (low + high)
        low, high = (middle, high) if check(middle) else (low, middle)
    return low


def bending_limit(p):
    """2/ω of the bob's fastest swing on the cable as a massless pinned-clamped beam: the
    beam's end (deflection v across the cable, slope φ) has the stiffness
    3EI/L³ [[1, -L], [-L, L²]] (singular: the rigid turn about the pivot, v = Lφ); the bob
    (its centre of mass c beyond the clamp along the cable) the mass matrix
    [[M, Mc], [Mc, Mc² + I]]."""
    ei, length, m, c = p.bending_stiffness, p.length, p.mass, p.half_size[2]
    stiffness = 3.0 * ei / length**3 * np.array([[1.0, -length], [-length, length**2]])
    mass = np.array([[m, m * c], [m * c, m * c * c + p.inertia()[1]]])
    omega2 = np.linalg.eigvals(np.linalg.solve(mass, stiffness)).real.max()
    return 2.0 / math.sqrt(omega2)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dt", type=float, default=0.002, help="time step, s")
    parser.add_argument("--duration", type=float, default=10.0, help="simulated time, s")
    parser.add_argument("--stability", action="store_true", help="bisect the largest stable dt")
    args = parser.parse_args()

    p = Pendulum(dt=args.dt, duration=args.duration)
    times, angles, _ = swing(p)
    measured = period(times, angles)
    analytic, rigid = p.analytic_period(), p.rigid_period()
    print(f"bob {p.mass} kg, cable {p.linear_density * p.length * 1e3:.3g} g, dt {p.dt} s")
    print(f"period measured {measured:.6f} s")
    print(f"period analytic {analytic:.6f} s  relative error {measured / analytic - 1:+.2e}")
    print(f"with the cable's mass {rigid:.6f} s  relative error {measured / rigid - 1:+.2e}")
    if args.stability:
        scale = math.sqrt(p.mass * p.length / p.stretch_stiffness)
        bending = bending_limit(p)
        limit = stability_limit(p, guess=min(2.0 * scale, bending))
        print(f"largest stable dt {limit:.6f} s = {limit / scale:.3f} sqrt(M L/EA)")
        print(f"predicted: axial 2 sqrt(M L/EA) = {2.0 * scale:.6f} s, bending {bending:.6f} s")


if __name__ == "__main__":
    main()
