#!/usr/bin/env python3
"""Seeded generator of random, valid spatial mechanisms as lsmbs case files ("dimension": 3;
docs/case-format.md, "Spatial cases").

    gen_spatial.py --seed N [-o case.json] [--family F] [--solid]

Importable: ``generate(seed, family=None, solid=False) -> dict``. The family is chosen by the seed
(``FAMILY_CYCLE[seed % 6]``); everything else is drawn from ``random.Random(seed)``:

- ``chain``         1-3 rods hung from the ground by spherical, universal or revolute joints with
                    random axes, each joined to the next by one of them; released under gravity
                    with an initial spin of the first rod (consistent with its joint);
- ``slider_crank``  crank (revolute about a random axis), connecting rod with a spherical joint
                    at the crank pin and a universal joint at the slider, slider on a prismatic
                    joint whose line is offset out of the crank's plane; driven by a ramp law on
                    the crank's joint angle, or free with an initial crank speed; a spring on the
                    slider;
- ``pendulum``      a body on a spherical, cylindrical or planar joint, held by one or two spatial
                    spring–dampers, loaded by a force or a torque in the ground or the body frame
                    (constant or ramp laws), a torsion spring on a cylindrical joint's angle.

With ``solid=True`` (``--solid``) the family comes from ``SOLID_CYCLE[seed % 3]`` instead, a
flexible 3D solid body (a box of enhanced hexahedra, docs/case-format.md "Solid bodies") in each:

- ``solid_cantilever`` a bar clamped to the ground at one end, a rigid tip body tied to the
                    other loaded by a force (constant or ramp), gravity along a random direction;
- ``solid_arm``     a plate clamped to a hub turned by a motor (a speed ramp) about an axis
                    across the plate, a payload at its tip; a hole drilled through the plate
                    (its radius a design variable: a 3D level set);
- ``solid_pendulum`` a bar tied to a rigid hub on a spherical joint, released with a spin about
                    a random axis (large 3D rotations of a flexible body).

Design variables of the solid families: E, ρ, ν, the tip body's mass, the load scale, the hole's
radius; responses: a face's mean position, the elongation between the end faces, the strain and
kinetic energies, the aggregated von Mises stress, the mass.

Every body has mass and three positive principal moments obeying the triangle inequality, at a
random orientation. Joints are assembled where the bodies are (the frames coincide at t = 0), so
the initial configuration is exactly closed; initial velocities are given for one body only and the
loader's projection computes the others (it keeps what is given). ωh stays below 0.02. Design
variables bind model parameters (masses, principal moments, spring stiffness, damping and free
length, load scales, torsion stiffness); responses are smooth aggregates (final, average,
integral, rms) of positions, velocities, body axes, angular velocities, joint angles and
translations and the kinetic energy, never of what a driver prescribes.
"""
import argparse
import json
import math
import random

FAMILY_CYCLE = ["chain", "slider_crank", "pendulum", "chain", "pendulum", "slider_crank"]
SOLID_CYCLE = ["solid_cantilever", "solid_arm", "solid_pendulum"]
G = 9.81


def unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def add(a, b, s=1.0):
    return [x + s * y for x, y in zip(a, b)]


def random_dir(rng):
    while True:
        v = [rng.uniform(-1, 1) for _ in range(3)]
        n = math.sqrt(dot(v, v))
        if 0.2 < n <= 1:
            return [x / n for x in v]


def perpendicular(rng, n):
    """A random unit vector perpendicular to the unit vector n."""
    while True:
        v = random_dir(rng)
        w = add(v, n, -dot(v, n))
        if dot(w, w) > 0.1:
            return unit(w)


def rotation(rng):
    """A random rotation matrix (rows), from a random unit quaternion."""
    q = unit([rng.gauss(0, 1) for _ in range(4)])
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def frame_along(e3, hint):
    """Rows of a rotation whose third column is e3."""
    e1 = unit(add(hint, e3, -dot(hint, e3)))
    e2 = cross(e3, e1)
    return [[e1[i], e2[i], e3[i]] for i in range(3)]


def rod_inertia(rng, m, length):
    # a slender rod along e3: I3 = a I small, I2 = (1 − a b) I with b ≤ 1/2, so that
    # I1 ≤ I2 + I3 holds with a margin of a I / 2 (a rigid body's principal moments)
    I = m * length * length / 12
    a, b = rng.uniform(0.02, 0.2), rng.uniform(0.0, 0.5)
    return [I, I * (1 - a * b), I * a]


def box_inertia(rng, m):
    a, b, c = (rng.uniform(0.03, 0.12) for _ in range(3))
    return [m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12]


class Builder:
    def __init__(self, seed, rng):
        self.seed, self.rng = seed, rng
        self.bodies, self.joints, self.forces, self.measures = [], [], [], []
        self.params = []     # (parameter, value, lower, upper)
        self.responses = []  # (measure column, aggregate)
        self.choices = {}
        self.variables_extra, self.geometry = [], None  # design variables of a level set
        self.gravity = [0, 0, -G]
        self.h = rng.choice([1e-3, 5e-4])
        self.t_end = rng.choice([0.3, 0.5])

    def body(self, name, m, inertia, position, orientation, **extra):
        b = {"name": name, "type": "rigid", "mass": m, "inertia": inertia,
             "position": position, "orientation": orientation}
        b.update(extra)
        self.bodies.append(b)
        return b

    def param(self, name, value, spread=0.5):
        self.params.append((name, value, value * (1 - spread), value * (1 + spread)))

    def measure(self, m, columns, aggregates=("final", "average", "rms", "integral")):
        self.measures.append(m)
        for c in columns:
            self.responses.append((c, self.rng.choice(aggregates)))


def gen_chain(B):
    rng = B.rng
    n = rng.randint(1, 3)
    B.choices["links"] = n
    pivot = [0.0, 0.0, 0.0]
    prev = "ground"
    for i in range(n):
        length = rng.uniform(0.15, 0.4)
        d = unit(add(random_dir(rng), [0, 0, -0.8]))  # hanging, roughly
        m = rng.uniform(0.3, 2.0)
        name = "link%d" % i
        centre = add(pivot, d, length / 2)
        kind = rng.choice(["spherical", "universal", "revolute"])
        B.choices["joint%d" % i] = kind
        extra = {}
        j = {"name": "j%d" % i, "type": kind, "a": prev, "b": name, "at": pivot}
        if kind == "revolute":
            j["axis"] = perpendicular(rng, d)
        elif kind == "universal":
            ax = perpendicular(rng, d)
            j["axis"], j["axis_b"] = ax, unit(cross(d, ax))
        if i == 0:  # an initial spin the first joint allows (a revolute: about its axis)
            w = j["axis"] if kind == "revolute" else random_dir(rng)
            if kind == "universal":
                w = j["axis"]
            speed = rng.uniform(0.5, 5.0)
            extra["angular_velocity"] = [speed * x for x in w]
            extra["velocity"] = [speed * x for x in cross(w, add(centre, pivot, -1))]
        B.body(name, m, rod_inertia(rng, m, length), centre, frame_along(d, random_dir(rng)), **extra)
        B.joints.append(j)
        B.param(name + ".mass", m)
        if rng.random() < 0.5:  # within ±30 %, I3 keeps the triangle inequality (rod_inertia)
            B.param(name + ".I3", B.bodies[-1]["inertia"][2], 0.3)
        tip = add(pivot, d, length)
        B.measure({"name": name + "_tip", "type": "position", "body": name, "at": tip},
                  [name + "_tip." + rng.choice("xyz")])
        if kind == "revolute":
            B.measure({"name": name + "_angle", "type": "joint_angle", "joint": "j%d" % i},
                      [name + "_angle"])
        prev, pivot = name, tip
    B.measure({"name": "spin", "type": "angular_velocity", "body": "link0",
               "frame": rng.choice(["ground", "body"])}, ["spin." + rng.choice("xyz")],
              ("average", "rms", "integral"))
    B.measure({"name": "energy", "type": "kinetic_energy"}, ["energy"], ("average", "integral"))


def gen_slider_crank(B):
    rng = B.rng
    r, L = rng.uniform(0.04, 0.1), rng.uniform(0.2, 0.35)
    e = rng.uniform(0.3, 0.7) * math.sqrt(L * L - r * r)  # the slider's offset from the crank plane
    axis = random_dir(rng)  # the crank's axis
    u = perpendicular(rng, axis)  # the crank's direction at t = 0
    w = cross(axis, u)      # the slider moves along w, offset by e along the axis
    P = [r * x for x in u]
    s0 = math.sqrt(L * L - e * e)  # the slider's position along w when the pin is on u
    S = add(add([e * x for x in axis], u, r), w, s0)  # |S − P| = √(e² + s0²) = L
    d = unit(add(S, P, -1))
    mc, mr, ms = rng.uniform(0.2, 1.0), rng.uniform(0.3, 1.0), rng.uniform(0.2, 0.8)
    B.body("crank", mc, rod_inertia(rng, mc, r), [r / 2 * x for x in u], frame_along(u, axis))
    B.body("rod", mr, rod_inertia(rng, mr, L), add(P, add(S, P, -1), 0.5), frame_along(d, axis))
    B.body("slider", ms, box_inertia(rng, ms), S, rotation(rng))
    cross_b = unit(cross(d, axis))
    B.joints += [
        {"name": "bearing", "type": "revolute", "a": "ground", "b": "crank", "at": [0, 0, 0],
         "axis": axis},
        {"name": "pin", "type": "spherical", "a": "crank", "b": "rod", "at": P},
        {"name": "wrist", "type": "universal", "a": "slider", "b": "rod", "at": S, "axis": axis,
         "axis_b": cross_b},
        {"name": "slide", "type": "prismatic", "a": "ground", "b": "slider", "at": S, "axis": w}]
    driven = rng.random() < 0.5
    B.choices["driven"] = driven
    omega = rng.uniform(5, 0.02 / B.h)
    if driven:
        B.joints.append({"name": "motor", "type": "rotation_driver", "joint": "bearing",
                         "law": {"type": "ramp", "from": 0, "speed": omega,
                                 "ramp_time": rng.uniform(0.05, 0.2)}})
        B.measure({"name": "torque", "type": "constraint_force", "joint": "motor"}, ["torque.0"],
                  ("average", "rms", "integral"))
    else:
        B.bodies[0]["angular_velocity"] = [omega * x for x in axis]
        B.measure({"name": "crank_angle", "type": "joint_angle", "joint": "bearing"},
                  ["crank_angle"])
    k = rng.uniform(100, 2000)
    B.forces.append({"name": "spring", "type": "spring_damper", "a": "ground",
                     "a_at": add(S, w, 0.5), "b": "slider", "b_at": S, "stiffness": k,
                     "damping": rng.uniform(0.5, 5)})
    B.param("spring.stiffness", k)
    B.param("spring.damping", B.forces[-1]["damping"])
    B.param("rod.mass", mr)
    B.param("slider.mass", ms)
    B.measure({"name": "stroke", "type": "joint_translation", "joint": "slide"}, ["stroke"])
    B.measure({"name": "rod_axis", "type": "body_axis", "body": "rod", "axis": d},
              ["rod_axis." + rng.choice("xyz")])
    B.measure({"name": "energy", "type": "kinetic_energy"}, ["energy"], ("average", "integral"))


def gen_pendulum(B):
    rng = B.rng
    m = rng.uniform(0.5, 3.0)
    c = [rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), -rng.uniform(0.15, 0.3)]
    B.body("bob", m, box_inertia(rng, m), c, rotation(rng))
    B.param("bob.mass", m)
    kind = rng.choice(["spherical", "cylindrical", "planar"])
    B.choices["joint"] = kind
    j = {"name": "hinge", "type": kind, "a": "ground", "b": "bob", "at": [0, 0, 0]}
    if kind == "cylindrical":
        j["axis"] = random_dir(rng)
    elif kind == "planar":
        j["normal"] = random_dir(rng)
    B.joints.append(j)
    for i in range(rng.randint(1, 2)):
        anchor = [rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(0.1, 0.3)]
        at = add(c, random_dir(rng), 0.05)
        k = rng.uniform(50, 500)
        s = {"name": "spring%d" % i, "type": "spring_damper", "a": "ground", "a_at": anchor,
             "b": "bob", "b_at": at, "stiffness": k, "damping": rng.uniform(0.1, 2)}
        length = math.sqrt(sum((x - y) ** 2 for x, y in zip(anchor, at)))
        if rng.random() < 0.5:
            s["free_length"] = length * rng.uniform(0.8, 1.2)
            B.param("spring%d.free_length" % i, s["free_length"], 0.1)
        B.forces.append(s)
        B.param("spring%d.stiffness" % i, k)
    frame = rng.choice(["ground", "body"])
    if rng.random() < 0.5:
        f = {"name": "push", "type": "point_force", "body": "bob", "at": add(c, random_dir(rng), 0.04),
             "frame": frame}
        kind_load = "force"
    else:
        f = {"name": "push", "type": "torque", "body": "bob", "frame": frame}
        kind_load = "torque"
    amp = rng.uniform(0.5, 3.0) if kind_load == "force" else rng.uniform(0.05, 0.3)
    if rng.random() < 0.5:
        f[kind_load] = [amp * x for x in random_dir(rng)]
    else:
        keys = ("fx", "fy", "fz") if kind_load == "force" else ("tx", "ty", "tz")
        for key, x in zip(keys, random_dir(rng)):
            f[key] = {"type": "ramp", "from": 0, "speed": amp * x, "ramp_time": 0.1}
    B.choices["load"] = kind_load + "/" + frame
    B.forces.append(f)
    B.param("push.scale", 1.0)
    if kind == "cylindrical":
        k = rng.uniform(0.5, 5)
        B.forces.append({"name": "torsion", "type": "rotational_spring_damper", "joint": "hinge",
                         "stiffness": k, "damping": rng.uniform(0.01, 0.1)})
        B.param("torsion.stiffness", k)
        B.measure({"name": "turn", "type": "joint_angle", "joint": "hinge"}, ["turn"])
        B.measure({"name": "slide", "type": "joint_translation", "joint": "hinge"}, ["slide"])
    B.measure({"name": "bob", "type": "position", "body": "bob"}, ["bob." + rng.choice("xyz")])
    B.measure({"name": "bob_v", "type": "velocity", "body": "bob"}, ["bob_v." + rng.choice("xyz")],
              ("average", "rms", "integral"))
    B.measure({"name": "w", "type": "angular_velocity", "body": "bob",
               "frame": rng.choice(["ground", "body"])}, ["w." + rng.choice("xyz")],
              ("average", "rms", "integral"))


MATERIALS = {"steel": (2.1e11, 0.3, 7850), "aluminium": (7.0e10, 0.33, 2700)}


def solid_bar(B, name, length, width, depth, n, origin, subgrid=None):
    """A box solid body along x from origin: length × width (y) × depth (z), n × 1 × 1 bricks
    (n × 2 × 1 for a plate wider than deep); E, ρ, ν of a random metal, their parameters design
    candidates."""
    rng = B.rng
    metal = rng.choice(sorted(MATERIALS))
    E, nu, rho = MATERIALS[metal]
    B.choices["material"] = metal
    ny = 2 if width > 2 * depth else 1
    B.bodies.append({"name": name, "type": "solid",
                     "mesh": {"type": "box", "origin": origin, "size": [length, width, depth],
                              "elements": [n, ny, 1]},
                     "material": {"E": E, "nu": nu, "rho": rho}})
    B.param(name + ".E", E)
    B.param(name + ".rho", rho, 0.3)
    if rng.random() < 0.3:
        B.params.append((name + ".nu", nu, 0.2, 0.4))
    return E, rho


def solid_measures(B, name, far_face):
    rng = B.rng
    B.measure({"name": "tip", "type": "node_set_position", "body": name, "node_set": far_face},
              ["tip." + rng.choice("xyz")])
    B.measure({"name": "stretch", "type": "elongation", "body": name, "a": "xmin",
               "b": far_face}, ["stretch"])
    B.measure({"name": "se", "type": "strain_energy"}, ["se"], ("final", "average", "integral"))
    B.measure({"name": "energy", "type": "kinetic_energy"}, ["energy"], ("average", "integral"))


def stress_measure(B, name, sigma):
    B.measure({"name": "stress", "type": "stress", "body": name, "reference": sigma},
              ["stress"], ("final", "average"))


def gen_solid_cantilever(B):
    rng = B.rng
    L, w = rng.uniform(0.3, 0.8), rng.uniform(0.02, 0.05)
    n = rng.randint(4, 8)
    B.h, B.t_end = 5e-4, rng.choice([0.02, 0.04])
    E, rho = solid_bar(B, "bar", L, w, w, n, [0, -w / 2, -w / 2])
    mt = rng.uniform(0.2, 2.0)
    B.body("tip", mt, box_inertia(rng, mt), [L + 0.01, 0, 0], rotation(rng))
    B.param("tip.mass", mt)
    B.joints += [
        {"name": "clamp", "type": "solid_connection", "solid": "bar", "node_set": "xmin",
         "body": "ground"},
        {"name": "tie", "type": "solid_connection", "solid": "bar", "node_set": "xmax",
         "body": "tip"}]
    # a load of the order of the bar's weight times 1–10, across and along
    F = rng.uniform(1, 10) * rho * L * w * w * G
    f = {"name": "push", "type": "point_force", "body": "tip", "at": [L + 0.01, 0, 0]}
    d = unit(add(random_dir(rng), [1, 0, 0], rng.uniform(-0.5, 0.5)))
    if rng.random() < 0.5:
        f["force"] = [F * x for x in d]
        B.choices["load"] = "constant"
    else:
        for key, x in zip(("fx", "fy", "fz"), d):
            f[key] = {"type": "ramp", "from": 0, "speed": F * x / 0.01, "ramp_time": 0.01}
        B.choices["load"] = "ramp"
    B.forces.append(f)
    B.param("push.scale", 1.0)
    B.gravity = [G * x for x in random_dir(rng)]
    solid_measures(B, "bar", "xmax")
    # the root's bending stress of the load, F L / (w³/6), as the KS reference
    stress_measure(B, "bar", F * L * 6 / w ** 3)


def gen_solid_arm(B):
    rng = B.rng
    L, width, t = rng.uniform(0.2, 0.4), rng.uniform(0.04, 0.08), rng.uniform(0.006, 0.012)
    n = rng.choice([8, 10])
    B.h, B.t_end = 5e-4, 0.03
    solid_bar(B, "plate", L, width, t, n, [0, -width / 2, -t / 2])
    B.body("hub", 0.5, [1e-3, 1e-3, 1e-3], [0, 0, 0], rotation(rng))
    mp = rng.uniform(0.1, 1.0)
    B.body("payload", mp, box_inertia(rng, mp), [L + 0.01, 0, 0], rotation(rng))
    B.param("payload.mass", mp)
    angle = rng.uniform(0, math.pi)  # the hub's axis, across the plate (in the y–z plane)
    axis = [0, math.cos(angle), math.sin(angle)]
    B.choices["axis"] = "%.3f rad from y" % angle
    omega = rng.uniform(5, 15)
    B.joints += [
        {"name": "shoulder", "type": "revolute", "a": "ground", "b": "hub", "at": [0, 0, 0],
         "axis": axis},
        {"name": "motor", "type": "rotation_driver", "joint": "shoulder",
         "law": {"type": "ramp", "from": 0, "speed": omega, "ramp_time": 0.015}},
        {"name": "root", "type": "solid_connection", "solid": "plate", "node_set": "xmin",
         "body": "hub"},
        {"name": "tip", "type": "solid_connection", "solid": "plate", "node_set": "xmax",
         "body": "payload"}]
    r = rng.uniform(0.2, 0.3) * width
    B.variables_extra.append({"name": "r_hole", "initial": r, "lower": 0.5 * r,
                              "upper": min(1.5 * r, 0.4 * width)})
    B.geometry = [{"body": "plate", "subgrid": 8, "features": [
        {"name": "hole", "type": "through_hole", "face": "zmax", "profile": "circle",
         "cx": rng.uniform(0.3, 0.6) * L, "cy": 0, "r": "r_hole"}]}]
    B.gravity = [0, 0, -G]
    solid_measures(B, "plate", "xmax")
    B.measure({"name": "mass", "type": "mass", "body": "plate"}, ["mass"], ("final",))
    stress_measure(B, "plate", 1e7)


def gen_solid_pendulum(B):
    rng = B.rng
    L, w = rng.uniform(0.2, 0.5), rng.uniform(0.015, 0.04)
    n = rng.randint(4, 6)
    B.h, B.t_end = 5e-4, rng.choice([0.03, 0.05])
    solid_bar(B, "bar", L, w, w, n, [0, -w / 2, -w / 2])
    mh = rng.uniform(0.2, 1.0)
    spin = rng.uniform(2, 8)
    wdir = random_dir(rng)
    hub = B.body("hub", mh, box_inertia(rng, mh), [0, 0, 0], rotation(rng),
                 angular_velocity=[spin * x for x in wdir])
    hub["velocity"] = [0, 0, 0]
    B.param("hub.mass", mh)
    B.joints += [
        {"name": "ball", "type": "spherical", "a": "ground", "b": "hub", "at": [0, 0, 0]},
        {"name": "root", "type": "solid_connection", "solid": "bar", "node_set": "xmin",
         "body": "hub"}]
    B.gravity = [G * x for x in unit(add(random_dir(rng), [0, 0, -1.5]))]
    solid_measures(B, "bar", "xmax")
    stress_measure(B, "bar", 1e6)


GENERATORS = {"chain": gen_chain, "slider_crank": gen_slider_crank, "pendulum": gen_pendulum,
              "solid_cantilever": gen_solid_cantilever, "solid_arm": gen_solid_arm,
              "solid_pendulum": gen_solid_pendulum}


def generate(seed, family=None, solid=False):
    rng = random.Random(seed)
    cycle = SOLID_CYCLE if solid else FAMILY_CYCLE
    family = family or cycle[seed % len(cycle)]
    B = Builder(seed, rng)
    B.choices["family"] = family
    GENERATORS[family](B)
    responses, seen = [], set()
    for i, (col, agg) in enumerate(B.responses):
        name = "r%d_%s_%s" % (i, col.replace(".", "_"), agg)
        if name not in seen:
            seen.add(name)
            responses.append({"name": name, "measure": col, "aggregate": agg})
    picked = B.params if len(B.params) <= 4 else rng.sample(B.params, 4)
    variables, parameters = [], []
    for i, (p, v, lo, up) in enumerate(picked):
        variables.append({"name": "p%d" % i, "initial": v, "lower": lo, "upper": up})
        parameters.append({"parameter": p, "variable": "p%d" % i})
    design = {"variables": variables + B.variables_extra, "parameters": parameters}
    if B.geometry:
        design["geometry"] = B.geometry
    return {
        "name": "spatial_corpus_%d" % seed,
        "description": "gen_spatial.py seed %d (%s): %s" % (
            seed, family, "; ".join("%s=%s" % (k, v) for k, v in B.choices.items())),
        "_generator": dict({"seed": seed, "family": family, "spatial": True},
                           **({"solid": True} if solid else {})),
        "dimension": 3,
        "gravity": B.gravity,
        "bodies": B.bodies,
        "joints": B.joints,
        "forces": B.forces,
        "design": design,
        "simulation": {"t_end": B.t_end, "h": B.h},
        "output": {"measures": B.measures, "responses": responses},
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--family", choices=sorted(GENERATORS))
    ap.add_argument("--solid", action="store_true", help="the solid-body families (SOLID_CYCLE)")
    ap.add_argument("-o", "--out")
    a = ap.parse_args()
    text = json.dumps(generate(a.seed, a.family, a.solid), indent=1)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text + "\n")
    else:
        print(text)


if __name__ == "__main__":
    main()
