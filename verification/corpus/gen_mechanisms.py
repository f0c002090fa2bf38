#!/usr/bin/env python3
"""Seeded generator of random, valid planar mechanisms as lsmbs case files (docs/case-format.md).

    gen_mechanisms.py --seed N [-o case.json] [--family F] [--with-new-loads]

Importable: ``generate(seed, with_new_loads=False, family=None) -> dict`` returns the case.

The family is chosen by the seed (``FAMILY_CYCLE[seed % 10]``) so that every block of ten seeds
covers all families; everything else is drawn from ``random.Random(seed)``:

- ``chain``        pendulum chains of 1-4 links, revolute to ground; free, or one joint driven
                   (ground or relative) with the other joints free;
- ``fourbar``      Grashof crank-rockers (transmission angle kept in [30, 150] deg over a full
                   turn), free, or driven with a free pendulum hanging from the coupler;
- ``slider_crank`` crank / connecting rod / piston (prismatic), free, or driven with a spring-
                   mounted absorber on the piston or a pendulum on the piston;
- ``two_loop``     two closed loops: a V-twin (two pistons on one crank pin) or a crank-rocker
                   driving a slider through a second link (six-bar);
- ``flexible``     one coarse plane-stress plate (6x2 ... 12x2 quads, steel or aluminium):
                   a clamped cantilever, an arm (driven or free hub, ``rigid_connection``), or the
                   flexible connecting rod of a slider-crank (massless rigid end bodies).

Ingredients: offset centres of mass, massless links (only where the joints determine them: a
link with a point mass at its far end, a driven link, a link whose successor has mass and
inertia, connecting rods and couplers of closed loops, end bodies of a plate), ``point_mass``,
``spring_damper`` (anchored outside the reach of the mechanism so that its length never
vanishes), ``point_force`` (constant or trapezoid / ramp laws), rotation drivers (ramp and
trapezoid laws starting from rest), initial angular velocities (slow 0.5-5 rad/s or fast
10-50 rad/s, omega h <= 0.02), time steps 1e-3 ... 1.25e-4 s with at most 2,000 steps, default
Newton tolerance or a tight one. Design variables bind model parameters (stiffness, damping, free
length, masses, inertias, force scales: at least one load on an undriven degree of freedom, at
most one parameter of a driven body, no mass of a body pinned at its centre of mass) and, on
plates, a circle or ellipse hole (radius, centre or size factor; never starting at 0) kept inside
the plate and away from the connected edges. Responses are smooth aggregates (final, average,
integral, rms, ks) of position, angle, distance, elongation, kinetic and strain energy, never of
a measure the drivers prescribe.

Initial configurations are exactly closed (forward kinematics and loop closure here) and the
initial velocities are consistent with the constraints; ``check_case`` verifies both and that the
mass matrix is positive definite on the tangent space of the joints (every massless body
determined), treating a plate as a rigid body for that check.

``--with-new-loads`` (off by default; needs an lsmbs that knows them) adds ``torque`` forces,
``rotational_spring_damper`` elements at revolute joints, and ``angular_velocity`` / ``velocity``
measures.
"""
import argparse
import json
import math
import random
import sys

FAMILY_CYCLE = ["chain", "fourbar", "slider_crank", "flexible", "chain",
                "two_loop", "fourbar", "flexible", "slider_crank", "two_loop"]
H_CHOICES = [1e-3, 5e-4, 2.5e-4, 1.25e-4]
MAX_STEPS = 2000
G = 9.81

STEEL = {"E": 210e9, "nu": 0.3, "rho": 7800}
ALUMINIUM = {"E": 70e9, "nu": 0.33, "rho": 2700}


# ----------------------------------------------------------------------------- small vectors
def rot(a, v):
    c, s = math.cos(a), math.sin(a)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1])


def add(*vs):
    return (sum(v[0] for v in vs), sum(v[1] for v in vs))


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1])


def mul(k, v):
    return (k * v[0], k * v[1])


def norm(v):
    return math.hypot(v[0], v[1])


def perp(v):  # J v: rotation by +90 degrees (omega x r = omega * perp(r))
    return (-v[1], v[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1]


def circle_intersection(p0, r0, p1, r1, sign):
    """Intersection of circle(p0, r0) and circle(p1, r1); sign picks the branch (left of p0->p1 for +1)."""
    d = norm(sub(p1, p0))
    a = (r0 * r0 - r1 * r1 + d * d) / (2 * d)
    h2 = r0 * r0 - a * a
    if h2 < 0:
        return None
    h = math.sqrt(h2)
    u = mul(1 / d, sub(p1, p0))
    return add(p0, mul(a, u), mul(sign * h, perp(u)))


def solve2(a11, a12, a21, a22, b1, b2):
    det = a11 * a22 - a12 * a21
    return ((b1 * a22 - a12 * b2) / det, (a11 * b2 - a21 * b1) / det)


def r6(x):
    """Round for the JSON (keeps the file readable; exactness of closure is not needed to 1e-16)."""
    return float("%.15g" % x)


def v6(v):
    return [r6(v[0]), r6(v[1])]


# ----------------------------------------------------------------------------- the builder
class Builder:
    def __init__(self, seed, rng, with_new_loads):
        self.seed, self.rng, self.with_new = seed, rng, with_new_loads
        self.bodies, self.joints, self.forces = [], [], []
        self.measures = []      # (measure dict, [(column, kind, scale, informative)])
        self.candidates = []    # design candidates: dict(parameter, value, lower, upper)
        self.geometry = None    # (plate body, features, variables)
        self.names = set()
        self.choices = {}
        self.kinematic = set()  # bodies whose motion the drivers prescribe (their parameters act on nothing else)
        self.free_bodies = []   # rigid bodies with a free rotation (torque / angular velocity targets)
        self.free_revolutes = []  # (joint name, body a, body b or "ground")
        self.length = 0.1       # characteristic length of the mechanism (KS parameters, placements)
        self.omega = 1.0        # characteristic angular speed
        self.mass = 1.0         # characteristic mass

    # names
    def uname(self, base):
        n, i = base, 1
        while n in self.names:
            i += 1
            n = "%s%d" % (base, i)
        self.names.add(n)
        return n

    def u(self, a, b):
        return self.rng.uniform(a, b)

    def chance(self, p):
        return self.rng.random() < p

    # bodies
    def rigid(self, base, pos, angle, mass, inertia, com=(0.0, 0.0), vel=(0.0, 0.0), omega=0.0,
              design_mass=True, design_inertia=True, kinematic=False, pinned=False):
        """pinned: a revolute to ground at the reference point; with the centre of mass there too,
        the mass acts on nothing and is no design candidate."""
        name = self.uname(base)
        if pinned and com == (0.0, 0.0):
            design_mass = False
        if kinematic:
            self.kinematic.add(name)
        b = {"name": name, "type": "rigid", "position": v6(pos), "angle": r6(angle), "mass": r6(mass),
             "inertia": r6(inertia)}
        if com != (0.0, 0.0):
            b["com"] = v6(com)
        if vel != (0.0, 0.0):
            b["velocity"] = v6(vel)
        if omega != 0.0:
            b["angular_velocity"] = r6(omega)
        self.bodies.append(b)
        if mass > 0 and design_mass:
            self.cand(name + ".mass", mass, 0.5, 2.0, not kinematic)
        if inertia > 0 and design_inertia:
            self.cand(name + ".inertia", inertia, 0.5, 2.0, not kinematic)
        return name

    def cand(self, parameter, value, lo_f, hi_f, free=True, load=False):
        """A design candidate; free: it acts on a degree of freedom that no driver prescribes;
        load: a force parameter (without one, masses of a single free body would scale out)."""
        self.candidates.append({"parameter": parameter, "value": value, "lower": value * lo_f,
                                "upper": value * hi_f, "free": free, "load": load})

    def is_free(self, *points):
        return any("body" in p and p["body"] not in self.kinematic for p in points)

    def ensure_free_load(self, point, direction_angle=None):
        """Adds a point force on `point` unless a spring or force already acts on a free body."""
        if any(c["load"] and c["free"] for c in self.candidates):
            return
        F = self.mass * (G + self.omega ** 2 * self.length) * self.u(0.05, 0.4)
        ang = self.u(-math.pi, math.pi) if direction_angle is None else direction_angle
        self.force("load", point, rot(ang, (F, 0)))

    def link_inertia(self, mass, length, width=None):
        width = width if width is not None else 0.15 * length
        return mass * (length ** 2 + width ** 2) / 12.0 * self.u(0.6, 1.5)

    # joints
    def revolute(self, base, a, a_at, b, b_at=None):
        name = self.uname(base)
        j = {"name": name, "type": "revolute", "a": {"body": a, "at": v6(a_at)}}
        j["b"] = "ground" if b == "ground" else {"body": b, "at": v6(b_at)}
        self.joints.append(j)
        return name

    def prismatic(self, base, body, direction):
        name = self.uname(base)
        self.joints.append({"name": name, "type": "prismatic", "a": {"body": body, "at": [0, 0]},
                            "direction": v6(direction)})
        return name

    def driver(self, base, body, relative_to, s0, speed):
        """Rotation driver from rest: ramp or trapezoid law starting at s0 (speed signed)."""
        name = self.uname(base)
        t_end = self.t_end
        start = 0.0 if self.chance(0.7) else r6(self.u(0.0, 0.25) * t_end)
        if self.chance(0.5):
            ramp_time = r6(self.u(0.1, 0.6) * t_end)
            law = {"type": "ramp", "from": r6(s0), "speed": r6(speed), "ramp_time": ramp_time}
            kind = "ramp"
        else:
            ta = self.u(0.1, 0.4) * t_end
            dist = abs(speed) * self.u(0.6, 1.5) * t_end
            law = {"type": "trapezoid", "from": r6(s0), "to": r6(s0 + math.copysign(dist, speed)),
                   "acceleration": r6(abs(speed) / ta), "speed": r6(abs(speed))}
            kind = "trapezoid"
        if start:
            law["start"] = start
        j = {"name": name, "type": "rotation_driver", "body": body, "law": law}
        if relative_to != "ground":
            j["relative_to"] = relative_to
        self.joints.append(j)
        self.choices.setdefault("drivers", []).append("%s on %s rel. %s, %s law, %.3g rad/s" %
                                                      (name, body, relative_to, kind, speed))
        return name

    # forces
    def point_mass(self, base, point, mass, design=True):
        name = self.uname(base)
        self.forces.append({"name": name, "type": "point_mass", "point": point, "mass": r6(mass)})
        if design:
            self.cand(name + ".mass", mass, 0.5, 2.0, self.is_free(point))
        return name

    def spring(self, base, a, b, d0, mass_eff, wn, design=True):
        """Spring-damper with natural frequency wn for the mass mass_eff, damping ratio 2-30 %."""
        name = self.uname(base)
        k = mass_eff * wn * wn
        zeta = self.u(0.02, 0.3)
        c = 2 * zeta * math.sqrt(k * mass_eff)
        free = d0 * self.u(0.75, 1.25)
        self.forces.append({"name": name, "type": "spring_damper", "a": a, "b": b, "stiffness": r6(k),
                            "damping": r6(c), "free_length": r6(free)})
        if design:
            fr = self.is_free(a, b)
            self.cand(name + ".stiffness", k, 0.5, 2.0, fr, True)
            self.cand(name + ".damping", c, 0.5, 2.0, fr, True)
            self.cand(name + ".free_length", free, 0.85, 1.15, fr, True)
        self.choices.setdefault("springs", []).append("%s: wn %.3g rad/s, zeta %.2f" % (name, wn, zeta))
        return name

    def force(self, base, point, fvec, design=True):
        """Point force of vector fvec: constant, or both components following one ramp/trapezoid law."""
        name = self.uname(base)
        f = {"name": name, "type": "point_force", "point": point}
        mode = self.rng.choice(["constant", "trapezoid", "ramp"])
        if mode == "constant":
            f["force"] = v6(fvec)
        else:
            t_end = self.t_end
            for key, comp in (("fx", fvec[0]), ("fy", fvec[1])):
                if abs(comp) < 1e-12:
                    continue
                if mode == "trapezoid":
                    ta = self.u(0.1, 0.4) * t_end
                    tt = self.u(0.5, 1.2) * t_end   # time to reach the full force
                    speed = abs(comp) / max(tt - ta, 0.3 * tt)
                    f[key] = {"type": "trapezoid", "from": 0, "to": r6(comp), "acceleration": r6(speed / ta),
                              "speed": r6(speed)}
                else:
                    f[key] = {"type": "ramp", "from": 0, "speed": r6(comp / t_end),
                              "ramp_time": r6(self.u(0.1, 0.5) * t_end)}
        if design:
            f["scale"] = 1.0
            self.cand(name + ".scale", 1.0, 0.5, 2.0, self.is_free(point), True)
        self.forces.append(f)
        self.choices.setdefault("forces", []).append("%s: %s, |F| %.3g N" % (name, mode, norm(fvec)))
        return name

    # new loads (flag): torque on a body, rotational spring at a revolute joint
    def new_loads(self):
        if not self.with_new:
            return
        if self.free_bodies:
            body, jeff = self.rng.choice(self.free_bodies)
            name = self.uname("torque")
            T = jeff * self.omega ** 2 * self.u(0.2, 1.0) * self.rng.choice([-1, 1]) + 1e-3
            self.forces.append({"name": name, "type": "torque", "body": body, "torque": r6(T)})
            self.cand(name + ".scale", 1.0, 0.5, 2.0, True, True)
        if self.free_revolutes:
            _, a, b, jeff = self.rng.choice(self.free_revolutes)
            name = self.uname("rot_spring")
            wn = self.omega * self.u(0.5, 2.0) + 1.0
            k = jeff * wn * wn
            c = 2 * self.u(0.02, 0.3) * math.sqrt(k * jeff)
            self.forces.append({"name": name, "type": "rotational_spring_damper", "a": a, "b": b,
                                "stiffness": r6(k), "damping": r6(c)})
            self.cand(name + ".stiffness", k, 0.5, 2.0, True, True)
            self.cand(name + ".damping", c, 0.5, 2.0, True, True)
        if self.free_bodies:
            body, _ = self.rng.choice(self.free_bodies)
            self.measure({"type": "angular_velocity", "body": body}, "w_" + body, [("", "angvel")])

    # measures: cols = [(suffix, kind)], kind in pos, angle, dist, elong, ke, se, angvel, vel
    def measure(self, m, base, cols, informative=True):
        name = self.uname("m_" + base)
        m = dict(m)
        m["name"] = name
        out = []
        for suffix, kind in cols:
            out.append((name + suffix, kind, informative))
        self.measures.append((m, out))
        return name

    def position_measure(self, base, point, informative=True):
        self.measure({"type": "position", "point": point}, base, [(".x", "pos"), (".y", "pos")], informative)
        if self.with_new and informative and "body" in point and self.chance(0.5):
            self.measure({"type": "velocity", "point": point}, "v_" + base, [(".x", "vel"), (".y", "vel")])


# ----------------------------------------------------------------------------- families
def setup_common(B, family):
    rng = B.rng
    B.h = rng.choice(H_CHOICES)
    t_end = B.u(0.05, 0.4)
    if family == "flexible":
        t_end = B.u(0.05, 0.25)
    n = max(20, min(MAX_STEPS, int(round(t_end / B.h))))
    B.n_steps = n
    B.t_end = r6(n * B.h)
    B.tight = B.chance(0.35)
    B.tol_r = rng.choice([1e-11, 1e-12]) if B.tight else None
    B.rho_inf = None if B.chance(0.7) else rng.choice([0.5, 0.6, 0.9])
    B.gravity = B.chance(0.6)
    B.fast = B.chance(0.5)
    # fast: omega * h <= 0.02 (a free 4-link chain at 31 rad/s with h = 1 ms gains energy until
    # Newton fails: seed 174 before this cap; chains whip, so keep a margin)
    B.omega = B.u(10, min(50.0, max(12.0, 0.02 / B.h))) if B.fast else B.u(0.5, 5)
    B.choices.update({"h": B.h, "steps": n, "t_end": B.t_end,
                      "tolerance": ("tol_r %g" % B.tol_r) if B.tight else "default",
                      "rho_inf": B.rho_inf if B.rho_inf is not None else "default 0.8",
                      "gravity": B.gravity, "speed": "fast" if B.fast else "slow"})


def signed(B, w):
    return w * B.rng.choice([-1, 1])


def gen_chain(B):
    n = B.rng.randint(1, 4)
    if n >= 3 and B.h > 5e-4:
        # free chains of 3-4 links whip: at h = 1 ms generalized-alpha gains energy until Newton
        # fails (seed 174 of an earlier version, 4 links at 13 rad/s with a 1.3 kN load)
        B.h = 5e-4
        B.n_steps = min(MAX_STEPS, 2 * B.n_steps)
        B.t_end = r6(B.n_steps * B.h)
        B.choices.update({"h": B.h, "steps": B.n_steps, "t_end": B.t_end})
    driven = n >= 2 and B.chance(0.5)
    k_drv = B.rng.randrange(n) if driven else -1
    if driven and k_drv == n - 1 and B.chance(0.5):
        k_drv = 0
    B.choices.update({"links": n, "motion": ("driven joint %d" % k_drv) if driven else "free"})
    pivot = (B.u(-0.2, 0.2), B.u(-0.2, 0.2))
    L = [B.u(0.1, 0.5) for _ in range(n)]
    th = [B.u(-math.pi, math.pi) for _ in range(n)]
    B.length = sum(L)
    # masses: "rigid" (offset com), "pm" (massless link + point mass at its end), "massless"
    kinds = []
    for i in range(n):
        r = B.rng.random()
        if i == k_drv and r < 0.3:
            kinds.append("massless")      # a driven link is determined by its joint and driver
        elif r < 0.25:
            kinds.append("pm")
        else:
            kinds.append("rigid")
    for i in range(n - 1):  # an undriven massless link needs a massive successor with inertia
        if kinds[i] == "massless" and i != k_drv and kinds[i + 1] != "rigid":
            kinds[i] = "pm"
    B.choices["link_kinds"] = kinds
    # angular velocities (absolute); a driver starts from rest relative to its reference
    w = []
    for i in range(n):
        wi = signed(B, B.omega * B.u(0.3, 1.0)) if B.chance(0.7) else 0.0
        w.append(wi)
    if driven:
        w[k_drv] = w[k_drv - 1] if k_drv > 0 else 0.0
    P = [pivot]
    V = [(0.0, 0.0)]
    for i in range(n):
        d = rot(th[i], (L[i], 0))
        P.append(add(P[i], d))
        V.append(add(V[i], mul(w[i], perp(d))))
    names, masses = [], []
    mtot = 0.0
    for i in range(n):
        if kinds[i] == "rigid":
            m = B.u(0.1, 2.0)
            com = (L[i] * B.u(0.3, 0.7), L[i] * B.u(-0.15, 0.15)) if B.chance(0.7) else (0.0, 0.0)
            J = B.link_inertia(m, L[i])
        else:
            m, J, com = 0.0, 0.0, (0.0, 0.0)
        masses.append(m)
        nm = B.rigid("link%d" % (i + 1), P[i], th[i], m, J, com, V[i], w[i], kinematic=(driven and i == k_drv == 0),
                     pinned=(i == 0))
        names.append(nm)
        if kinds[i] == "pm":
            pm = B.u(0.1, 2.0)
            B.point_mass("bob%d" % (i + 1), {"body": nm, "at": [r6(L[i]), 0]}, pm)
            m = pm
        mtot += m
    B.mass = max(mtot, 0.1)
    for i in range(n):
        if i == 0:
            jn = B.revolute("pin1", names[0], (0, 0), "ground")
            prev = "ground"
        else:
            jn = B.revolute("pin%d" % (i + 1), names[i - 1], (L[i - 1], 0), names[i], (0, 0))
            prev = names[i - 1]
        if i == k_drv:
            s0 = th[i] - (th[i - 1] if i > 0 else 0.0)
            B.driver("drive%d" % (i + 1), names[i], prev, s0, signed(B, B.omega * B.u(0.5, 1.0)))
        else:
            jeff = max(masses[i], 0.05) * L[i] ** 2 / 3
            B.free_revolutes.append((jn, names[i], prev, jeff))
            if kinds[i] == "rigid":
                B.free_bodies.append((names[i], jeff))
    # forces
    if B.chance(0.6):
        j = B.rng.randrange(n)
        at = (L[j] * B.u(0.3, 1.0), 0.0)
        anchor = add(pivot, rot(B.u(-math.pi, math.pi), (B.length + B.u(0.1, 0.5), 0)))
        p = add(P[j], rot(th[j], at))
        B.spring("spring", {"body": names[j], "at": v6(at)}, {"ground": v6(anchor)}, norm(sub(p, anchor)),
                 B.mass, B.omega * B.u(0.5, 2.0) + 2.0)
    if B.chance(0.5) or (not B.gravity and all(x == 0 for x in w) and not driven):
        j = B.rng.randrange(n)
        F = B.mass * (G + B.omega ** 2 * B.length) * B.u(0.05, 0.4)
        B.force("push", {"body": names[j], "at": [r6(L[j]), 0]}, rot(B.u(-math.pi, math.pi), (F, 0)))
    B.ensure_free_load({"body": names[-1], "at": [r6(L[-1]), 0]})
    B.new_loads()
    # measures
    tip = {"body": names[-1], "at": [r6(L[-1]), 0]}
    B.position_measure("tip", tip)
    free_links = [names[i] for i in range(n) if not (driven and i == k_drv == 0)]
    if free_links:
        B.measure({"type": "angle", "body": B.rng.choice(free_links)}, "angle", [("", "angle")])
    B.measure({"type": "kinetic_energy"}, "ke", [("", "ke")])
    ref = (pivot[0] + B.u(-0.3, 0.3), pivot[1] - B.length - 0.05)
    B.measure({"type": "distance", "a": tip, "b": {"ground": v6(ref)}}, "tip_dist", [("", "dist")])
    for f in B.forces:
        if f["type"] == "spring_damper":
            B.measure({"type": "elongation", "a": f["a"], "b": f["b"]}, "stretch", [("", "elong")])


def fourbar_geometry(B, scale):
    """Grashof crank-rocker (crank a shortest): returns a, b, c, d and the branch sign."""
    for _ in range(200):
        d = scale
        a = d * B.u(0.15, 0.35)
        b = d * B.u(0.6, 1.4)
        c = d * B.u(0.6, 1.4)
        lmax = max(b, c, d)
        if a + lmax > a + b + c + d - a - lmax - 0.08 * d:   # s + l < p + q with a margin
            continue
        lo, hi = math.pi, 0.0
        for k in range(72):  # transmission angle over a full turn
            t = 2 * math.pi * k / 72
            bd2 = a * a + d * d - 2 * a * d * math.cos(t)
            cm = (b * b + c * c - bd2) / (2 * b * c)
            if abs(cm) >= 1:
                lo = -1
                break
            mu = math.acos(cm)
            lo, hi = min(lo, mu), max(hi, mu)
        if lo >= math.radians(30) and hi <= math.radians(150):
            return a, b, c, d
    raise RuntimeError("no four-bar found")


def fourbar_pose(A, D, a, b, c, theta, sign):
    Bp = add(A, rot(theta, (a, 0)))
    C = circle_intersection(Bp, b, D, c, sign)
    return Bp, C


def fourbar_velocity(A, Bp, C, D, wa):
    """Coupler and rocker angular velocities for crank speed wa: wa*(B-A) + wb*(C-B) = wc*(C-D)."""
    ra, rb, rc = sub(Bp, A), sub(C, Bp), sub(C, D)
    # wb*rb - wc*rc = -wa*ra   (perp is invertible and linear: drop it)
    wb, wc = solve2(rb[0], -rc[0], rb[1], -rc[1], -wa * ra[0], -wa * ra[1])
    return wb, wc


def add_pendulum(B, host, host_at, P, vP, base="pendulum"):
    """Free pendulum hanging from a point of a host body (an extra free degree of freedom)."""
    Lp = B.length * B.u(0.3, 0.8)
    psi = B.u(-math.pi, math.pi)
    wp = signed(B, B.omega * B.u(0.2, 1.0)) if B.chance(0.5) else 0.0
    if B.chance(0.3):
        nm = B.rigid(base, P, psi, 0.0, 0.0, vel=vP, omega=wp)
        B.point_mass(base + "_bob", {"body": nm, "at": [r6(Lp), 0]}, B.mass * B.u(0.1, 0.5))
        jeff = B.mass * 0.3 * Lp * Lp
    else:
        m = B.mass * B.u(0.1, 0.5)
        nm = B.rigid(base, P, psi, m, B.link_inertia(m, Lp), (Lp * B.u(0.4, 0.8), 0.0), vP, wp)
        jeff = m * Lp * Lp / 3
        B.free_bodies.append((nm, jeff))
    jn = B.revolute(base + "_pin", host, host_at, nm, (0, 0))
    B.free_revolutes.append((jn, nm, host, jeff))
    tip = {"body": nm, "at": [r6(Lp), 0]}
    if B.chance(0.5):
        anchor = add(P, rot(B.u(-math.pi, math.pi), (B.length * 3 + Lp + 0.2, 0)))
        tp = add(P, rot(psi, (Lp, 0)))
        B.spring(base + "_spring", tip, {"ground": v6(anchor)}, norm(sub(tp, anchor)), B.mass * 0.3,
                 B.omega * B.u(0.3, 1.5) + 2.0)
    else:
        F = B.mass * 0.3 * (G + B.omega ** 2 * Lp) * B.u(0.05, 0.4)
        B.force(base + "_load", tip, rot(B.u(-math.pi, math.pi), (F, 0)))
    B.position_measure(base + "_tip", tip)
    B.measure({"type": "angle", "body": nm}, base + "_angle", [("", "angle")])
    B.choices["pendulum"] = "on %s, length %.3g" % (host, Lp)
    return nm, tip


def gen_fourbar(B):
    scale = B.u(0.1, 0.5)
    B.length = scale
    a, b, c, d = fourbar_geometry(B, scale)
    beta = B.u(-math.pi, math.pi)
    A = (B.u(-0.1, 0.1), B.u(-0.1, 0.1))
    D = add(A, rot(beta, (d, 0)))
    sign = B.rng.choice([-1, 1])
    theta = B.u(-math.pi, math.pi)
    Bp, C = fourbar_pose(A, D, a, b, c, theta, sign)
    driven = B.chance(0.5)
    B.choices.update({"links": [a, b, c, d], "branch": sign, "motion": "driven" if driven else "free"})
    wa = 0.0 if driven else signed(B, B.omega * B.u(0.5, 1.0))
    wb, wc = fourbar_velocity(A, Bp, C, D, wa)
    th_b = math.atan2(C[1] - Bp[1], C[0] - Bp[0])
    th_c = math.atan2(C[1] - D[1], C[0] - D[0])
    B.mass = B.u(0.2, 2.0)
    mc = B.mass * B.u(0.3, 1.0)
    crank_massless = driven and B.chance(0.3)
    coupler_massless = B.chance(0.25)
    kin = driven
    if crank_massless:
        crank = B.rigid("crank", A, theta, 0.0, 0.0, kinematic=kin)
    else:
        com = (a * B.u(-0.3, 0.5), a * B.u(-0.1, 0.1)) if B.chance(0.6) else (0.0, 0.0)
        crank = B.rigid("crank", A, theta, mc, B.link_inertia(mc, a, 0.5 * a), com, (0, 0), wa, kinematic=kin,
                        pinned=True)
    vB = mul(wa, perp(sub(Bp, A)))
    if coupler_massless:
        coupler = B.rigid("coupler", Bp, th_b, 0.0, 0.0, vel=vB, omega=wb, kinematic=kin)
    else:
        m = B.mass * B.u(0.3, 1.0)
        coupler = B.rigid("coupler", Bp, th_b, m, B.link_inertia(m, b), (b * B.u(0.3, 0.7), b * B.u(-0.3, 0.3)),
                          vB, wb, kinematic=kin)
    m = B.mass * B.u(0.3, 1.0)
    rocker = B.rigid("rocker", D, th_c, m, B.link_inertia(m, c), (c * B.u(0.3, 0.7), 0.0), (0, 0), wc,
                     kinematic=kin)
    B.choices["massless"] = [n for n, f in (("crank", crank_massless), ("coupler", coupler_massless)) if f]
    B.revolute("pivot_a", crank, (0, 0), "ground")
    B.revolute("crank_pin", crank, (a, 0), coupler, (0, 0))
    B.revolute("rocker_pin", coupler, (b, 0), rocker, (c, 0))
    B.revolute("pivot_d", rocker, (0, 0), "ground")
    # coupler point
    cp_local = (b * B.u(0.2, 0.8), b * B.u(-0.5, 0.5))
    cp = add(Bp, rot(th_b, cp_local))
    vcp = add(vB, mul(wb, perp(rot(th_b, cp_local))))
    cpt = {"body": coupler, "at": v6(cp_local)}
    B.position_measure("coupler_point", cpt, informative=not driven)
    if B.chance(0.4):
        B.point_mass("coupler_mass", cpt, B.mass * B.u(0.1, 0.5))
    reach = norm(sub(D, A)) + b + c + a
    if driven:
        B.driver("motor", crank, "ground", theta, signed(B, B.omega * B.u(0.5, 1.0)))
        add_pendulum(B, coupler, cp_local, cp, vcp)
        B.length = scale
    else:
        B.free_bodies.append((rocker, m * c * c / 3))
        B.measure({"type": "angle", "body": rocker}, "rocker_angle", [("", "angle")])
        B.measure({"type": "angle", "body": crank}, "crank_angle", [("", "angle")])
    if B.chance(0.6):
        anchor = add(A, rot(B.u(-math.pi, math.pi), (reach + B.u(0.05, 0.3), 0)))
        B.spring("spring", cpt, {"ground": v6(anchor)}, norm(sub(cp, anchor)), B.mass,
                 B.omega * B.u(0.3, 1.5) + 2.0)
    if B.chance(0.5) or (not driven and not B.gravity):
        F = B.mass * (G + B.omega ** 2 * scale) * B.u(0.05, 0.4)
        B.force("push", {"body": rocker, "at": [r6(c), 0]}, rot(B.u(-math.pi, math.pi), (F, 0)))
    B.ensure_free_load({"body": rocker, "at": [r6(c), 0]})
    B.new_loads()
    B.measure({"type": "kinetic_energy"}, "ke", [("", "ke")])
    for f in B.forces:
        if f["type"] == "spring_damper":
            B.measure({"type": "elongation", "a": f["a"], "b": f["b"]}, "stretch", [("", "elong")],
                      informative=not driven)
    B.measure({"type": "distance", "a": cpt, "b": {"ground": v6(add(A, (0, -reach)))}}, "cp_dist",
              [("", "dist")], informative=not driven)


def slider_pose(O, phi, e, Bp, l):
    """Piston on the line through O + e*n (direction u = (cos phi, sin phi)) at distance l from Bp."""
    u = rot(phi, (1, 0))
    nrm = perp(u)
    loc = (dot(sub(Bp, O), u), dot(sub(Bp, O), nrm))
    dy = e - loc[1]
    if abs(dy) >= l:
        return None
    x = loc[0] + math.sqrt(l * l - dy * dy)
    return add(O, mul(x, u), mul(e, nrm))


def slider_velocity(Bp, P, vB, phi):
    """vB + w * perp(P - B) = s * u: returns (w, s)."""
    u = rot(phi, (1, 0))
    r = perp(sub(P, Bp))
    w, s = solve2(r[0], -u[0], r[1], -u[1], -vB[0], -vB[1])
    return w, s


def add_slider(B, crank, crank_pin_local, O, phi, e, Bp, vB, l, tag, rod_massless, piston_mass, kin):
    P = slider_pose(O, phi, e, Bp, l)
    th_rod = math.atan2(P[1] - Bp[1], P[0] - Bp[0])
    w_rod, s = slider_velocity(Bp, P, vB, phi)
    u = rot(phi, (1, 0))
    if rod_massless:
        rod = B.rigid("rod" + tag, Bp, th_rod, 0.0, 0.0, vel=vB, omega=w_rod, kinematic=kin)
    else:
        m = piston_mass * B.u(0.3, 1.0)
        rod = B.rigid("rod" + tag, Bp, th_rod, m, B.link_inertia(m, l), (l * B.u(0.3, 0.6), 0.0), vB, w_rod,
                      kinematic=kin)
    piston = B.rigid("piston" + tag, P, 0.0, piston_mass, 0.0, vel=mul(s, u), design_inertia=False, kinematic=kin)
    B.revolute("crank_pin" + tag, crank, crank_pin_local, rod, (0, 0))
    B.revolute("gudgeon" + tag, rod, (l, 0), piston, (0, 0))
    B.prismatic("cylinder" + tag, piston, u)
    return rod, piston, P, s


def gen_slider_crank(B, vtwin=False):
    r = B.u(0.03, 0.15)
    l = r * B.u(2.5, 4.5)
    B.length = l + r
    O = (B.u(-0.1, 0.1), B.u(-0.1, 0.1))
    phi = B.u(-math.pi, math.pi)
    e = r * B.u(-0.4, 0.4)
    theta = B.u(-math.pi, math.pi)
    driven = B.chance(0.5)
    B.mass = B.u(0.2, 2.0)
    wa = 0.0 if driven else signed(B, B.omega * B.u(0.5, 1.0))
    Bp = add(O, rot(theta, (r, 0)))
    vB = mul(wa, perp(sub(Bp, O)))
    mc = B.mass * B.u(0.5, 2.0)
    crank_massless = driven and B.chance(0.3)
    if crank_massless:
        crank = B.rigid("crank", O, theta, 0.0, 0.0, kinematic=driven)
    else:
        com = (r * B.u(-0.5, 0.5), r * B.u(-0.2, 0.2)) if B.chance(0.6) else (0.0, 0.0)
        crank = B.rigid("crank", O, theta, mc, B.link_inertia(mc, r, r), com, (0, 0), wa, kinematic=driven,
                        pinned=True)
    B.revolute("main_bearing", crank, (0, 0), "ground")
    rod_massless = B.chance(0.25)
    pm = B.mass * B.u(0.3, 1.0)
    rod, piston, P, s = add_slider(B, crank, (r, 0), O, phi, e, Bp, vB, l, "", rod_massless, pm, driven)
    pistons = [(piston, P, phi, e)]
    B.choices.update({"crank": r, "rod": l, "offset": e, "motion": "driven" if driven else "free",
                      "massless": [x for x, f in (("crank", crank_massless), ("rod", rod_massless)) if f]})
    if vtwin:
        phi2 = phi + B.rng.choice([-1, 1]) * math.radians(B.u(60, 120))
        l2 = r * B.u(2.5, 4.5)
        rod2_massless = B.chance(0.25)
        rod2, piston2, P2, s2 = add_slider(B, crank, (r, 0), O, phi2, 0.0, Bp, vB, l2, "_b", rod2_massless,
                                           B.mass * B.u(0.3, 1.0), driven)
        pistons.append((piston2, P2, phi2, 0.0))
        B.length = max(l, l2) + r
        B.choices["second_cylinder"] = "rod %.3g at %.1f deg" % (l2, math.degrees(phi2 - phi))
    # springs on the pistons: ground anchor on the axis beyond the top dead centre
    for (pn, Pp, ph, ee) in pistons:
        if B.chance(0.6):
            u = rot(ph, (1, 0))
            lmax = B.length + abs(ee)
            anchor = add(O, mul(lmax + r * B.u(0.3, 1.5), u), mul(ee, perp(u)))
            B.spring("spring_" + pn, {"body": pn, "at": [0, 0]}, {"ground": v6(anchor)}, norm(sub(Pp, anchor)),
                     B.mass, B.omega * B.u(0.3, 1.5) + 2.0)
        if B.chance(0.4):
            u = rot(ph, (1, 0))
            F = B.mass * (G + B.omega ** 2 * r) * B.u(0.05, 0.4) * B.rng.choice([-1, 1])
            B.force("gas_" + pn, {"body": pn, "at": [0, 0]}, mul(F, u))
    if driven:
        B.driver("motor", crank, "ground", theta, signed(B, B.omega * B.u(0.5, 1.0)))
        pn, Pp, ph, ee = pistons[0]
        if B.chance(0.5):
            u = rot(ph, (1, 0))
            d0 = r * B.u(1.0, 2.0) * B.rng.choice([-1, 1])
            ma = B.mass * B.u(0.1, 0.5)
            ab = B.rigid("absorber", add(Pp, mul(d0, u)), 0.0, ma, 0.0, design_inertia=False)
            B.prismatic("absorber_guide", ab, u)
            B.spring("absorber_spring", {"body": pn, "at": [0, 0]}, {"body": ab, "at": [0, 0]}, abs(d0), ma,
                     B.omega * B.u(3.0, 6.0) + 5.0)
            B.position_measure("absorber", {"body": ab, "at": [0, 0]})
            B.choices["absorber"] = "mass %.3g on %s" % (ma, pn)
        else:
            add_pendulum(B, pn, (0, 0), Pp, (0, 0))
    else:
        B.free_bodies.append((crank, mc * r * r))
        B.measure({"type": "angle", "body": crank}, "crank_angle", [("", "angle")])
        B.measure({"type": "angle", "body": rod}, "rod_angle", [("", "angle")])
        B.ensure_free_load({"body": pistons[0][0], "at": [0, 0]}, pistons[0][2])
    B.new_loads()
    for (pn, Pp, ph, ee) in pistons:
        B.position_measure(pn, {"body": pn, "at": [0, 0]}, informative=not driven)
    B.measure({"type": "kinetic_energy"}, "ke", [("", "ke")])
    B.measure({"type": "distance", "a": {"body": pistons[0][0], "at": [0, 0]}, "b": {"ground": v6(O)}},
              "stroke", [("", "dist")], informative=not driven)
    for f in B.forces:
        if f["type"] == "spring_damper":
            B.measure({"type": "elongation", "a": f["a"], "b": f["b"]}, "stretch", [("", "elong")],
                      informative=not driven or f["name"].startswith("absorber"))


def gen_fourbar_slider(B):
    """Crank-rocker whose rocker drives a slider through a second link: two closed loops (six-bar)."""
    scale = B.u(0.1, 0.4)
    B.length = scale
    a, b, c, d = fourbar_geometry(B, scale)
    beta = B.u(-math.pi, math.pi)
    A = (0.0, 0.0)
    D = add(A, rot(beta, (d, 0)))
    sign = B.rng.choice([-1, 1])
    c2 = c * B.u(0.8, 1.5)          # rocker output point (on the rocker line, beyond C or before)
    # rocker angle range over a full crank turn -> output point range
    pts = []
    for k in range(120):
        t = 2 * math.pi * k / 120
        Bp, C = fourbar_pose(A, D, a, b, c, t, sign)
        psi = math.atan2(C[1] - D[1], C[0] - D[0])
        pts.append(add(D, rot(psi, (c2, 0))))
    phi = B.u(-math.pi, math.pi)     # slider direction
    u = rot(phi, (1, 0))
    nrm = perp(u)
    ys = [dot(p, nrm) for p in pts]
    ymid = 0.5 * (max(ys) + min(ys))
    half = 0.5 * (max(ys) - min(ys))
    e_len = max(half, 0.05 * scale) / B.u(0.3, 0.6) + 0.1 * scale
    ys_line = ymid + B.u(-0.3, 0.3) * (e_len - half)
    theta = B.u(-math.pi, math.pi)
    Bp, C = fourbar_pose(A, D, a, b, c, theta, sign)
    driven = B.chance(0.5)
    B.mass = B.u(0.2, 2.0)
    wa = 0.0 if driven else signed(B, B.omega * B.u(0.5, 1.0))
    wb, wc = fourbar_velocity(A, Bp, C, D, wa)
    th_b = math.atan2(C[1] - Bp[1], C[0] - Bp[0])
    th_c = math.atan2(C[1] - D[1], C[0] - D[0])
    R = add(D, rot(th_c, (c2, 0)))
    vR = mul(wc, perp(sub(R, D)))
    S = slider_pose(A, phi, ys_line, R, e_len)
    w_e, s = slider_velocity(R, S, vR, phi)
    th_e = math.atan2(S[1] - R[1], S[0] - R[0])
    B.choices.update({"links": [a, b, c, d], "output": c2, "link": e_len, "motion": "driven" if driven else "free"})
    kin = driven
    mc = B.mass * B.u(0.3, 1.0)
    crank = B.rigid("crank", A, theta, mc, B.link_inertia(mc, a, 0.5 * a), (0, 0), (0, 0), wa, kinematic=kin,
                    pinned=True)
    vB = mul(wa, perp(sub(Bp, A)))
    m = B.mass * B.u(0.3, 1.0)
    coupler = B.rigid("coupler", Bp, th_b, m, B.link_inertia(m, b), (b * 0.5, 0.0), vB, wb, kinematic=kin)
    m = B.mass * B.u(0.3, 1.0)
    rocker = B.rigid("rocker", D, th_c, m, B.link_inertia(m, c2), (c2 * B.u(0.3, 0.6), 0.0), (0, 0), wc,
                     kinematic=kin)
    link_massless = B.chance(0.4)
    if link_massless:
        link = B.rigid("link", R, th_e, 0.0, 0.0, vel=vR, omega=w_e, kinematic=kin)
    else:
        m = B.mass * B.u(0.2, 0.6)
        link = B.rigid("link", R, th_e, m, B.link_inertia(m, e_len), (e_len * 0.5, 0.0), vR, w_e, kinematic=kin)
    ms = B.mass * B.u(0.3, 1.0)
    slider = B.rigid("slider", S, 0.0, ms, 0.0, vel=mul(s, u), design_inertia=False, kinematic=kin)
    B.choices["massless"] = ["link"] if link_massless else []
    B.revolute("pivot_a", crank, (0, 0), "ground")
    B.revolute("crank_pin", crank, (a, 0), coupler, (0, 0))
    B.revolute("rocker_pin", coupler, (b, 0), rocker, (c, 0))
    B.revolute("pivot_d", rocker, (0, 0), "ground")
    B.revolute("output_pin", rocker, (c2, 0), link, (0, 0))
    B.revolute("slider_pin", link, (e_len, 0), slider, (0, 0))
    B.prismatic("guide", slider, u)
    reach = d + c2 + e_len + 0.1
    if B.chance(0.7):
        anchor = add(S, mul(2 * reach, u))
        B.spring("spring", {"body": slider, "at": [0, 0]}, {"ground": v6(anchor)}, norm(sub(S, anchor)), B.mass,
                 B.omega * B.u(0.3, 1.5) + 2.0)
    if B.chance(0.5) or (not driven and not B.gravity):
        F = B.mass * (G + B.omega ** 2 * scale) * B.u(0.05, 0.4) * B.rng.choice([-1, 1])
        B.force("push", {"body": slider, "at": [0, 0]}, mul(F, u))
    if driven:
        B.driver("motor", crank, "ground", theta, signed(B, B.omega * B.u(0.5, 1.0)))
        add_pendulum(B, slider, (0, 0), S, (0, 0))
    else:
        B.free_bodies.append((rocker, m * c2 * c2 / 3))
        B.measure({"type": "angle", "body": rocker}, "rocker_angle", [("", "angle")])
        B.measure({"type": "angle", "body": link}, "link_angle", [("", "angle")])
        B.ensure_free_load({"body": slider, "at": [0, 0]}, phi)
    B.new_loads()
    B.position_measure("slider", {"body": slider, "at": [0, 0]}, informative=not driven)
    B.measure({"type": "kinetic_energy"}, "ke", [("", "ke")])
    for f in B.forces:
        if f["type"] == "spring_damper":
            B.measure({"type": "elongation", "a": f["a"], "b": f["b"]}, "stretch", [("", "elong")],
                      informative=not driven)


def gen_two_loop(B):
    if B.chance(0.5):
        B.choices["kind"] = "vtwin"
        gen_slider_crank(B, vtwin=True)
    else:
        B.choices["kind"] = "fourbar_slider"
        gen_fourbar_slider(B)


# ----------------------------------------------------------------------------- flexible
def plate_body(B, name, x0, L, H, origin, angle, vel=(0.0, 0.0), omega=0.0):
    nx = B.rng.randint(6, 12)
    ny = 2
    mat = STEEL if B.chance(0.5) else ALUMINIUM
    t = B.u(0.002, 0.01)
    b = {"name": name, "type": "flexible",
         "mesh": {"type": "rectangle", "origin": [r6(x0), r6(-H / 2)], "size": [r6(L), r6(H)], "elements": [nx, ny]},
         "placement": {"origin": v6(origin), "angle": r6(angle)},
         "material": dict(mat), "thickness": r6(t)}
    if vel != (0.0, 0.0):
        b["velocity"] = v6(vel)
    if omega != 0.0:
        b["angular_velocity"] = r6(omega)
    B.names.add(name)
    B.bodies.append(b)
    E = mat["E"]
    I = t * H ** 3 / 12
    mass = mat["rho"] * t * H * L
    B.choices["plate"] = "%s %dx%d, %.3g x %.3g m, t %.3g mm, %s" % (
        name, nx, ny, L, H, t * 1e3, "steel" if mat is STEEL else "aluminium")
    return {"name": name, "x0": x0, "L": L, "H": H, "EI": E * I, "mass": mass, "nx": nx}


def plate_hole(B, plate):
    """A circle or ellipse hole inside the plate, away from both ends; 1-2 design variables."""
    L, H, x0 = plate["L"], plate["H"], plate["x0"]
    feats, vars_ = [], []
    # keep the hole in the middle 40 % of the length, its extent below 0.38 H from the centre line
    cx = x0 + L * B.u(0.35, 0.65)
    kind = B.rng.choice(["circle_r", "circle_rc", "ellipse_d", "ellipse_c"])
    if kind.startswith("circle"):
        cy = H * B.u(-0.08, 0.08)
        rmax = min(0.38 * H - abs(cy), 0.12 * L)
        r = rmax * B.u(0.45, 0.7)
        vars_.append({"name": "hole_r", "initial": r6(r), "lower": r6(0.6 * r), "upper": r6(min(1.35 * r, rmax))})
        f = {"name": "hole", "type": "circle", "cx": r6(cx), "cy": r6(cy), "r": "hole_r"}
        if kind == "circle_rc":
            dx = 0.08 * L
            vars_.append({"name": "hole_cx", "initial": r6(cx), "lower": r6(cx - dx), "upper": r6(cx + dx)})
            f["cx"] = "hole_cx"
    else:
        a = min(0.1 * L, 0.3 * H) * B.u(0.6, 1.0)
        b = 0.3 * H * B.u(0.5, 0.9)
        ang = B.u(-0.4, 0.4)
        ext = max(a, b)
        dmax = 0.36 * H / ext
        d = min(1.0, dmax) * B.u(0.6, 0.8)
        cy = 0.0
        f = {"name": "hole", "type": "ellipse", "cx": r6(cx), "cy": r6(cy), "a": r6(a), "b": r6(b), "d": "hole_d",
             "angle": r6(ang)}
        vars_.append({"name": "hole_d", "initial": r6(d), "lower": r6(0.7 * d), "upper": r6(min(1.3 * d, dmax))})
        if kind == "ellipse_c":
            dy = max(0.0, 0.36 * H - ext * min(1.3 * d, dmax)) * 0.8
            if dy > 1e-4 * H:
                # never start a variable at 0: lsmbs's relative steps are then 1e-2 x its range, and the
                # fd reference drowns in round-off (an earlier version's seed 7)
                cy0 = dy * B.u(0.3, 0.7) * B.rng.choice([-1, 1])
                vars_.append({"name": "hole_cy", "initial": r6(cy0), "lower": r6(-dy), "upper": r6(dy)})
                f["cy"] = "hole_cy"
    feats.append(f)
    B.geometry = {"body": plate["name"], "features": feats}
    B.geometry_vars = vars_
    B.choices["hole"] = kind


def gen_flexible(B):
    kind = B.rng.choice(["cantilever", "arm", "rod"])
    B.choices["kind"] = kind
    if kind == "cantilever":
        L = B.u(0.2, 0.6)
        H = L * B.u(0.05, 0.12)
        ang = B.u(-math.pi, math.pi)
        O = (0.0, 0.0)
        plate = plate_body(B, "beam", 0.0, L, H, O, ang)
        B.length = L
        B.joints.append({"name": B.uname("root"), "type": "clamp", "flexible": "beam", "node_set": "left"})
        tip = {"body": "beam", "nearest": [r6(L), 0]}
        mid = {"body": "beam", "nearest": [r6(0.5 * L), 0]}
        mtip = plate["mass"] * B.u(0.2, 2.0)
        B.point_mass("tip_mass", tip, mtip)
        B.mass = plate["mass"] + mtip
        # transverse tip force giving a static deflection of 0.05-0.5 % of the length
        delta = L * B.u(5e-4, 5e-3)
        F = 3 * plate["EI"] * delta / L ** 3
        B.force("tip_load", tip, rot(ang, (F * B.u(-0.2, 0.2), F * B.rng.choice([-1, 1]))))
        B.position_measure("tip", tip)
        B.measure({"type": "elongation", "a": mid, "b": tip}, "beam_stretch", [("", "elong_flex")])
    elif kind == "arm":
        L = B.u(0.3, 0.8)
        H = L * B.u(0.05, 0.1)
        r0 = L * B.u(0.0, 0.2)
        th = B.u(-math.pi, math.pi)
        driven = B.chance(0.6)
        w0 = 0.0 if driven else signed(B, B.omega * B.u(0.3, 1.0))
        if not driven and not B.gravity and w0 == 0.0:
            B.gravity = True
        B.choices["motion"] = "driven" if driven else "free"
        hub_mass = 0.0 if B.chance(0.5) else B.u(0.2, 2.0)
        hub = B.rigid("hub", (0.0, 0.0), th, hub_mass, B.link_inertia(hub_mass, 0.1) if hub_mass else 0.0,
                      omega=w0, pinned=True)
        B.revolute("shoulder", hub, (0, 0), "ground")
        plate = plate_body(B, "arm", r0, L, H, (0.0, 0.0), th, omega=w0)
        B.length = r0 + L
        B.joints.append({"name": B.uname("root_connection"), "type": "rigid_connection", "rigid": hub,
                         "flexible": "arm", "node_set": "left"})
        tip_pt = add(rot(th, (r0 + L, 0)))
        mtip = plate["mass"] * B.u(0.3, 3.0)
        if B.chance(0.5):
            tipb = B.rigid("tip_body", tip_pt, th, 0.0, 0.0, vel=mul(w0, perp(tip_pt)), omega=w0)
            B.joints.append({"name": B.uname("tip_connection"), "type": "rigid_connection", "rigid": tipb,
                             "flexible": "arm", "node_set": "right"})
            off = L * B.u(0.05, 0.2)
            tip = {"body": tipb, "at": [r6(off), 0]}
        else:
            tip = {"body": "arm", "nearest": [r6(r0 + L), 0]}
        B.point_mass("payload", tip, mtip)
        B.mass = plate["mass"] + mtip
        if driven:
            B.driver("motor", hub, "ground", th, signed(B, B.omega * B.u(0.3, 1.0)))
        else:
            B.measure({"type": "angle", "body": hub}, "hub_angle", [("", "angle")])
        if B.chance(0.4):
            anchor = rot(B.u(-math.pi, math.pi), (B.length + B.u(0.1, 0.4), 0))
            tp = tip_pt if "at" not in tip else add(tip_pt, rot(th, (tip["at"][0], 0)))
            B.spring("spring", tip, {"ground": v6(anchor)}, norm(sub(tp, anchor)), B.mass,
                     B.omega * B.u(0.3, 1.0) + 2.0)
        B.position_measure("tip", tip)
        a = {"body": "arm", "nearest": [r6(r0), 0]}
        b = {"body": "arm", "nearest": [r6(r0 + L), 0]}
        B.measure({"type": "elongation", "a": a, "b": b}, "arm_stretch", [("", "elong_flex")])
    else:  # flexible connecting rod of a slider-crank
        r = B.u(0.03, 0.1)
        l = r * B.u(2.5, 4.0)
        H = l * B.u(0.08, 0.15)
        O = (0.0, 0.0)
        phi = B.u(-math.pi, math.pi)
        theta = B.u(-math.pi, math.pi)
        driven = B.chance(0.6)
        B.choices["motion"] = "driven" if driven else "free"
        wa = 0.0 if driven else signed(B, B.omega * B.u(0.5, 1.0))
        Bp = rot(theta, (r, 0))
        vB = mul(wa, perp(Bp))
        P = slider_pose(O, phi, 0.0, Bp, l)
        th_rod = math.atan2(P[1] - Bp[1], P[0] - Bp[0])
        w_rod, s = slider_velocity(Bp, P, vB, phi)
        u = rot(phi, (1, 0))
        mc = B.u(0.5, 3.0)
        crank = B.rigid("crank", O, theta, mc, B.link_inertia(mc, r, r), (0, 0), (0, 0), wa, pinned=True)
        big = B.rigid("big_end", Bp, th_rod, 0.0, 0.0, vel=vB, omega=w_rod)
        plate = plate_body(B, "conrod", 0.0, l, H, Bp, th_rod, vel=vB, omega=w_rod)
        small = B.rigid("small_end", P, th_rod, 0.0, 0.0, vel=mul(s, u), omega=w_rod)
        mp = plate["mass"] * B.u(1.0, 5.0)
        piston = B.rigid("piston", P, 0.0, mp, 0.0, vel=mul(s, u), design_inertia=False)
        B.length = l + r
        B.mass = mp
        B.revolute("main_bearing", crank, (0, 0), "ground")
        B.revolute("crank_pin", crank, (r, 0), big, (0, 0))
        B.joints.append({"name": B.uname("big_end_connection"), "type": "rigid_connection", "rigid": big,
                         "flexible": "conrod", "node_set": "left"})
        B.joints.append({"name": B.uname("small_end_connection"), "type": "rigid_connection", "rigid": small,
                         "flexible": "conrod", "node_set": "right"})
        B.revolute("gudgeon", small, (0, 0), piston, (0, 0))
        B.prismatic("cylinder", piston, u)
        if driven:
            B.driver("motor", crank, "ground", theta, signed(B, B.omega * B.u(0.5, 1.0)))
        else:
            B.measure({"type": "angle", "body": crank}, "crank_angle", [("", "angle")])
        # gas-like load on the piston, pushing towards the crank
        F = (mp * B.omega ** 2 * r + 1.0) * B.u(0.5, 3.0)
        B.force("gas", {"body": piston, "at": [0, 0]}, mul(-F, u))
        B.position_measure("piston", {"body": piston, "at": [0, 0]}, informative=not driven)
        B.measure({"type": "elongation", "a": {"body": big, "at": [0, 0]}, "b": {"body": small, "at": [0, 0]}},
                  "rod_stretch", [("", "elong_flex")])
    plate_hole(B, plate)
    B.new_loads()
    B.measure({"type": "kinetic_energy"}, "ke", [("", "ke")])
    B.measure({"type": "strain_energy"}, "se", [("", "se")])


# ----------------------------------------------------------------------------- responses, design
AGGREGATES = {
    "pos": ["final", "average", "integral", "rms", "ks"],
    "angle": ["final", "average", "integral", "rms", "ks"],
    "dist": ["final", "average", "integral", "rms", "ks"],
    "elong": ["final", "average", "integral", "rms", "ks"],
    "elong_flex": ["final", "average", "integral", "rms"],
    "ke": ["final", "average", "integral", "rms"],
    "se": ["final", "average", "integral", "rms"],
    "angvel": ["final", "average", "integral", "rms"],
    "vel": ["final", "average", "integral", "rms"],
}


def make_responses(B):
    cols = [(c, k) for _, cs in B.measures for (c, k, inf) in cs if inf]
    energy = [(c, k) for c, k in cols if k in ("ke", "se")]
    n = B.rng.randint(3, 5)
    chosen, used = [], set()
    if energy:
        chosen.append((B.rng.choice(energy), "integral" if B.chance(0.5) else "average"))
        used.add(chosen[0])
    tries = 0
    while len(chosen) < n and tries < 100:
        tries += 1
        c, k = B.rng.choice(cols)
        agg = B.rng.choice(AGGREGATES[k])
        if ((c, k), agg) in used:
            continue
        used.add(((c, k), agg))
        chosen.append(((c, k), agg))
    out = []
    for i, ((c, k), agg) in enumerate(chosen):
        r = {"name": "r%d_%s_%s" % (i + 1, agg, c.replace("m_", "").replace(".", "_")), "measure": c,
             "aggregate": agg}
        if agg == "ks":
            scale = 1.0 if k == "angle" else B.length
            r["ks"] = r6(B.u(5, 40) / scale)
        if B.chance(0.15) and agg != "final":
            r["window"] = {"t0": r6(B.t_end * B.u(0.3, 0.6)), "t1": r6(B.t_end)}
        out.append(r)
    return out


def make_design(B):
    """1-4 parameter variables (1-3 with a plate hole): at least one load parameter acting on a free
    degree of freedom when there is one (without a load, the masses of a single free body scale
    out of its motion), the others preferably free; at most one parameter of a driven body."""
    variables, params = [], []
    geo_vars = getattr(B, "geometry_vars", [])
    n_par = B.rng.randint(1, 3) if geo_vars else B.rng.randint(2, 4)
    cands = list(B.candidates)
    B.rng.shuffle(cands)
    free_loads = [c for c in cands if c["free"] and c["load"]]
    free_other = [c for c in cands if c["free"] and not c["load"]]
    kin = [c for c in cands if not c["free"]]
    picked = free_loads[:1]
    rest = [c for c in free_loads[1:] + free_other if c not in picked]
    B.rng.shuffle(rest)
    if kin and B.chance(0.3):
        picked.append(kin[0])
    picked += rest[:max(0, n_par - len(picked))]
    if not picked:
        picked = kin[:n_par]
    for i, c in enumerate(picked[:n_par]):
        vn = "p%d" % (i + 1)
        variables.append({"name": vn, "initial": r6(c["value"]), "lower": r6(c["lower"]), "upper": r6(c["upper"])})
        params.append({"parameter": c["parameter"], "variable": vn})
    design = {"variables": variables + geo_vars}
    if B.geometry:
        design["geometry"] = [B.geometry]
    if params:
        design["parameters"] = params
    B.choices["design"] = [p["parameter"] for p in params] + [v["name"] for v in geo_vars]
    return design


def generate(seed, with_new_loads=False, family=None):
    rng = random.Random(seed)
    family = family or FAMILY_CYCLE[seed % len(FAMILY_CYCLE)]
    B = Builder(seed, rng, with_new_loads)
    B.choices["family"] = family
    setup_common(B, family)
    {"chain": gen_chain, "fourbar": gen_fourbar, "slider_crank": gen_slider_crank,
     "two_loop": gen_two_loop, "flexible": gen_flexible}[family](B)
    responses = make_responses(B)
    design = make_design(B)
    sim = {"t_end": B.t_end, "h": B.h}
    if B.tol_r is not None:
        sim["tol_r"] = B.tol_r
    if B.rho_inf is not None:
        sim["rho_inf"] = B.rho_inf
    case = {
        "name": "corpus_%d" % seed,
        "description": "gen_mechanisms.py seed %d (%s%s): %s" % (
            seed, family, ", new loads" if with_new_loads else "",
            "; ".join("%s=%s" % (k, fmt(v)) for k, v in B.choices.items())),
        "_generator": {"seed": seed, "family": family, "with_new_loads": with_new_loads},
        "gravity": [0, -G] if B.gravity else [0, 0],
        "bodies": B.bodies,
        "joints": B.joints,
        "forces": B.forces,
        "design": design,
        "simulation": sim,
        "output": {"measures": [m for m, _ in B.measures], "responses": responses},
    }
    check_case(case)
    return case


def fmt(v):
    if isinstance(v, float):
        return "%.4g" % v
    if isinstance(v, list):
        return "[" + ", ".join(fmt(x) for x in v) + "]"
    return str(v)


# ----------------------------------------------------------------------------- self-check
def _law_value(law):
    return law.get("from", law.get("value", 0.0)) if law["type"] != "table" else 0.0


def check_case(case, tol=1e-9):
    """Closure, velocity consistency and a positive definite mass matrix on the joints' tangent space.

    Plates are treated as rigid bodies (their nodes as body points; clamp and rigid_connection as
    welds). Raises AssertionError with the reason."""
    bodies = {}
    for b in case["bodies"]:
        if b["type"] == "rigid":
            bodies[b["name"]] = (tuple(b["position"]), b.get("angle", 0.0), tuple(b.get("velocity", (0, 0))),
                                 b.get("angular_velocity", 0.0))
        else:
            pl = b.get("placement", {})
            bodies[b["name"]] = (tuple(pl.get("origin", (0, 0))), pl.get("angle", 0.0),
                                 tuple(b.get("velocity", (0, 0))), b.get("angular_velocity", 0.0))
    names = list(bodies)
    idx = {n: 3 * i for i, n in enumerate(names)}
    nq = 3 * len(names)
    flex = {b["name"]: b for b in case["bodies"] if b["type"] == "flexible"}

    def local_of(pt):
        if "at" in pt:
            return tuple(pt["at"])
        if "nearest" in pt:
            return tuple(pt["nearest"])
        raise AssertionError("unsupported point %r" % pt)

    def point(pt):
        """(position, velocity, jacobian row pairs) of a point dict."""
        if "ground" in pt:
            return tuple(pt["ground"]), (0.0, 0.0), None
        b = pt["body"]
        p0, th, v0, w = bodies[b]
        s = rot(th, local_of(pt))
        return add(p0, s), add(v0, mul(w, perp(s))), (b, perp(s))

    rows, res, vres = [], [], []

    def point_rows(pa, pb):
        (xa, va, ja), (xb, vb, jb) = point(pa), point(pb)
        for k in range(2):
            row = [0.0] * nq
            for jj, sg in ((ja, 1.0), (jb, -1.0)):
                if jj:
                    row[idx[jj[0]] + k] += sg
                    row[idx[jj[0]] + 2] += sg * jj[1][k]
            rows.append(row)
            res.append(xa[k] - xb[k])
            vres.append(va[k] - vb[k])

    def weld_rows(a, b):
        for at in ((0.0, 0.0), (1.0, 0.0)):
            pa = {"body": a, "at": at}
            # point of a at `at`, expressed in b's frame at t = 0
            xa = point(pa)[0]
            if b == "ground":
                point_rows(pa, {"ground": xa})
            else:
                p0, th, _, _ = bodies[b]
                loc = rot(-th, sub(xa, p0))
                point_rows(pa, {"body": b, "at": loc})

    for j in case.get("joints", []):
        t = j["type"]
        if t == "revolute":
            b = j["b"]
            if b == "ground":
                b = {"ground": point(j["a"])[0]}
            point_rows(j["a"], b)
        elif t == "prismatic":
            x, v, jj = point(j["a"])
            uu = tuple(j["direction"])
            nn = perp(mul(1 / norm(uu), uu))
            row = [0.0] * nq
            row[idx[jj[0]]] = nn[0]
            row[idx[jj[0]] + 1] = nn[1]
            row[idx[jj[0]] + 2] = dot(nn, jj[1])
            rows.append(row)
            res.append(0.0)  # `through` defaults to the initial position
            vres.append(dot(nn, v))
            if j.get("lock_rotation", True):
                row = [0.0] * nq
                row[idx[jj[0]] + 2] = 1.0
                rows.append(row)
                res.append(0.0)
                vres.append(bodies[jj[0]][3])
        elif t == "rotation_driver":
            row = [0.0] * nq
            row[idx[j["body"]] + 2] = 1.0
            th, w = bodies[j["body"]][1], bodies[j["body"]][3]
            rel = j.get("relative_to", "ground")
            if rel != "ground":
                row[idx[rel] + 2] = -1.0
                th -= bodies[rel][1]
                w -= bodies[rel][3]
            rows.append(row)
            res.append(th - _law_value(j["law"]))
            vres.append(w)   # laws start from rest
        elif t == "rigid_connection":
            weld_rows(j["rigid"], j["flexible"])
        elif t == "clamp":
            weld_rows(j["flexible"], "ground")
        else:
            raise AssertionError("unsupported joint type " + t)
    L = max(1e-3, max(norm(v[0]) for v in bodies.values()))
    for r in res:
        assert abs(r) < tol * max(1.0, L) * 1e3, "initial configuration not closed: residual %g" % r
    vs = max([1.0] + [abs(v[3]) * L + norm(v[2]) for v in bodies.values()])
    for r in vres:
        assert abs(r) < 1e-8 * vs, "initial velocity inconsistent: residual %g" % r
    # mass matrix (rigid bodies with com offsets, point masses; plates as rigid rectangles)
    M = [[0.0] * nq for _ in range(nq)]

    def add_mass(b, m, J, c_local):
        if m == 0 and J == 0:
            return
        i = idx[b]
        c = rot(bodies[b][1], c_local)
        blk = [[m, 0, -m * c[1]], [0, m, m * c[0]], [-m * c[1], m * c[0], J + m * (c[0] ** 2 + c[1] ** 2)]]
        for r_ in range(3):
            for s_ in range(3):
                M[i + r_][i + s_] += blk[r_][s_]

    for b in case["bodies"]:
        if b["type"] == "rigid":
            add_mass(b["name"], b.get("mass", 0.0), b.get("inertia", 0.0), tuple(b.get("com", (0, 0))))
        else:
            me = b["mesh"]
            Lx, Ly = me["size"]
            m = b["material"]["rho"] * b["thickness"] * Lx * Ly
            c = (me["origin"][0] + Lx / 2, me["origin"][1] + Ly / 2)
            add_mass(b["name"], m, m * (Lx * Lx + Ly * Ly) / 12, c)
    for f in case.get("forces", []):
        if f["type"] == "point_mass":
            add_mass(f["point"]["body"], f["mass"], 0.0, local_of(f["point"]))
    # null space of the constraint Jacobian, then N^T M N > 0
    N = null_space(rows, nq)
    if not N:
        return
    K = [[sum(N[a][r_] * sum(M[r_][s_] * N[b][s_] for s_ in range(nq)) for r_ in range(nq))
          for b in range(len(N))] for a in range(len(N))]
    scale = max(abs(M[i][i]) for i in range(nq)) or 1.0
    assert cholesky_ok(K, 1e-10 * scale), "mass matrix singular on the constraint tangent space (massless body " \
                                          "not determined by its joints)"


def null_space(rows, n):
    """Orthonormal-free basis of {x : A x = 0} by Gauss-Jordan elimination (rows of A)."""
    A = [list(r) for r in rows]
    piv_cols, r = [], 0
    for c in range(n):
        p = max(range(r, len(A)), key=lambda i: abs(A[i][c]), default=None)
        if p is None or abs(A[p][c]) < 1e-10:
            continue
        A[r], A[p] = A[p], A[r]
        pv = A[r][c]
        A[r] = [x / pv for x in A[r]]
        for i in range(len(A)):
            if i != r and A[i][c] != 0:
                f = A[i][c]
                A[i] = [x - f * y for x, y in zip(A[i], A[r])]
        piv_cols.append(c)
        r += 1
        if r == len(A):
            break
    free = [c for c in range(n) if c not in piv_cols]
    basis = []
    for fc in free:
        x = [0.0] * n
        x[fc] = 1.0
        for i, pc in enumerate(piv_cols):
            x[pc] = -A[i][fc]
        nn = math.sqrt(sum(v * v for v in x))
        basis.append([v / nn for v in x])
    return basis


def cholesky_ok(K, floor):
    n = len(K)
    Lm = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i + 1):
            s = K[i][j] - sum(Lm[i][k] * Lm[j][k] for k in range(j))
            if i == j:
                if s <= floor:
                    return False
                Lm[i][j] = math.sqrt(s)
            else:
                Lm[i][j] = s / Lm[j][j]
    return True


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("-o", "--output", help="case file to write (default: stdout)")
    ap.add_argument("--family", choices=sorted(set(FAMILY_CYCLE)), help="override the seed's family")
    ap.add_argument("--with-new-loads", action="store_true",
                    help="also generate torque and rotational_spring_damper forces, angular_velocity and velocity "
                         "measures (needs an lsmbs that supports them)")
    a = ap.parse_args(argv)
    case = generate(a.seed, a.with_new_loads, a.family)
    text = json.dumps(case, indent=1) + "\n"
    if a.output:
        with open(a.output, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()
