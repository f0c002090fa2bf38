"""A planar case written as a spatial one ("dimension": 3), all motion in the plane z = 0.

    doc3, notes = to_spatial(json.load(open("data/andrews/andrews_squeezer.json")))

The same mechanism, in natural coordinates (docs/methods.md, "Spatial rigid bodies"); its
responses and gradients agree with the planar case's to the integrator's O(h²) error, not to
round-off (docs/methods.md says why, with the measured differences). Pure Python on the JSON
documents: no compiled module. scripts/planar_to_spatial.py is its command line.

How each planar kind is written (docs/case-format.md, "Planar cases as spatial ones"):

- a rigid body: its centre of mass at z = 0, principal axes (cos θ, sin θ, 0), (−sin θ, cos θ,
  0), (0, 0, 1), and the three moments J, J, J (the two out-of-plane ones only reach the
  constraint forces of planar motion; equal moments keep the triangle inequality);
- the joints form a spanning tree from the ground (prismatic joints first, then revolute joints
  that carry a driver or a rotational spring, then the others in file order): a revolute of the
  tree becomes a spatial revolute about z (5 equations), a prismatic a spatial prismatic; a
  revolute that closes a loop becomes an `inline` joint along z (2 equations: the planar
  revolute's own two), so that no equation repeats another; a group of bodies with no joint to
  the ground gets a `planar` joint (normal z) to it;
- drivers act on the joint angle (offset: the initial relative angle) or translation;
- a body's `angle` measure is the sum of the joint angles on its path from the ground plus its
  initial angle (a `combination`); `angular_velocity` is the z column of the spatial one;
- springs, torques, forces, gravity, the design parameters on them (a body's `inertia` on its
  three moments) carry over; the simulation, responses, conditions and optimization are copied.

Anything without a spatial counterpart here (flexible bodies, point masses, pressure loads, a
loop closed by a prismatic joint, …) raises ValueError naming the entry; measures no response
uses are left out with a note instead.
"""
import copy
import math

Z = [0.0, 0.0, 1.0]


class _Bodies:
    """The planar rigid bodies by name: reference point, angle, centre-of-mass offset."""

    def __init__(self, bodies):
        self.by_name = {}
        for i, b in enumerate(bodies):
            where = f"/bodies/{i}"
            if b.get("type", "rigid") != "rigid":
                raise ValueError(f"{where}: a {b.get('type')} body has no spatial counterpart here "
                                 "(spatial cases hold rigid bodies only)")
            self.by_name[b["name"]] = b

    def pose(self, name):
        b = self.by_name[name]
        return b.get("position", [0.0, 0.0]), float(b.get("angle", 0.0))

    def world(self, name, at):
        (px, py), th = self.pose(name)
        c, s = math.cos(th), math.sin(th)
        return [px + c * at[0] - s * at[1], py + s * at[0] + c * at[1]]


def _point(bodies, p, where, default_ground=None):
    """A planar point as (body or "ground", [x, y] at t = 0)."""
    if p == "ground":
        if default_ground is None:
            raise ValueError(f"{where}: \"ground\" without a point")
        return "ground", list(default_ground)
    if isinstance(p, dict) and "ground" in p:
        return "ground", [float(v) for v in p["ground"]]
    if isinstance(p, dict) and "body" in p:
        if p["body"] not in bodies.by_name:
            raise ValueError(f"{where}: '{p['body']}' is not a rigid body")
        if "at_global" in p:
            return p["body"], [float(v) for v in p["at_global"]]
        if "node" in p or "nearest" in p:
            raise ValueError(f"{where}: a node of a flexible body has no spatial counterpart here")
        return p["body"], bodies.world(p["body"], p.get("at", [0.0, 0.0]))
    raise ValueError(f"{where}: expected a point ({{\"body\", \"at\"}} or {{\"ground\": [x, y]}})")


def _xyz(p):
    return [float(p[0]), float(p[1]), 0.0]


class _Tree:
    """Union-find over the ground and the bodies: which joints close loops."""

    def __init__(self):
        self.up = {}

    def root(self, n):
        self.up.setdefault(n, n)
        while self.up[n] != n:
            self.up[n] = self.up[self.up[n]]
            n = self.up[n]
        return n

    def join(self, a, b):
        ra, rb = self.root(a), self.root(b)
        if ra == rb:
            return False
        self.up[ra] = rb
        return True


def to_spatial(doc, source="the planar case"):
    """The spatial document of a planar case document, and notes on what was left out."""
    if doc.get("dimension", 2) != 2:
        raise ValueError("/dimension: expected a planar case (dimension 2)")
    for key in ("initial_state",):
        if key in doc:
            raise ValueError(f"/{key}: not carried over (spatial cases do not take it)")
    bodies = _Bodies(doc.get("bodies", []))
    out = {k: copy.deepcopy(v) for k, v in doc.items()
           if k not in ("bodies", "joints", "forces", "output", "design", "gravity")}
    out["name"] = doc.get("name", "case") + "_spatial"
    out["description"] = (f"{source} written as a spatial case by scripts/planar_to_spatial.py "
                          "(all motion in z = 0). " + doc.get("description", ""))
    out["dimension"] = 3
    out["gravity"] = _xyz(doc.get("gravity", [0.0, 0.0]))
    out["bodies"] = [_body(b) for b in doc.get("bodies", [])]
    notes = []
    joints, info = _joints(doc.get("joints", []), doc.get("forces", []), bodies)
    out["joints"] = joints
    out["forces"] = _forces(doc.get("forces", []), bodies, info)
    if "output" in doc:
        out["output"] = _output(doc["output"], bodies, info, notes)
    if "design" in doc:
        out["design"] = _design(doc["design"], bodies)
    return out, notes


def _body(b):
    (px, py), th = b.get("position", [0.0, 0.0]), float(b.get("angle", 0.0))
    c, s = math.cos(th), math.sin(th)
    cx, cy = b.get("com", [0.0, 0.0])
    com = [px + c * cx - s * cy, py + s * cx + c * cy]
    J = float(b.get("inertia", 0.0))
    o = {"name": b["name"], "type": "rigid", "mass": float(b.get("mass", 0.0)), "inertia": [J, J, J],
         "position": _xyz(com), "orientation": {"axis": Z, "angle": th}}
    for k in ("comment",):
        if k in b:
            o[k] = b[k]
    w = float(b.get("angular_velocity", 0.0))
    if "angular_velocity" in b:
        o["angular_velocity"] = [0.0, 0.0, w]
    if "velocity" in b:  # of the reference point; spatial: of the centre of mass
        vx, vy = b["velocity"]
        rx, ry = com[0] - px, com[1] - py
        o["velocity"] = [vx - w * ry, vy + w * rx, 0.0]
    return o


def _joints(joints, forces, bodies):
    """The spatial joints, and per planar joint what it became (for drivers and measures)."""
    tree = _Tree()
    # the body pairs whose revolute joint must carry an angle: driven or sprung
    angled = {frozenset((j["body"], j.get("relative_to", "ground"))) for j in joints
              if j.get("type") == "rotation_driver"}
    angled |= {frozenset((f.get("a"), f.get("b", "ground"))) for f in forces
               if f.get("type") == "rotational_spring_damper"}

    def rank(i):
        kind = joints[i].get("type")
        if kind == "prismatic":
            return 0
        return 1 if kind == "revolute" and _pair(joints[i], bodies) in angled else 2

    order = sorted(range(len(joints)), key=lambda i: (rank(i), i))
    info = {"revolutes": {}, "prismatics": {}, "tree": {}, "forces": {}}
    spatial = {}
    for i in order:
        j, where = joints[i], f"/joints/{i}"
        kind = j.get("type")
        name = j.get("name", f"{kind}_{i}")
        if kind == "revolute":
            a, pa = _point(bodies, j.get("a"), where + "/a")
            b, pb = _point(bodies, j.get("b", "ground"), where + "/b", default_ground=pa)
            closes = not tree.join(a, b)
            # spatial x_b − x_a = planar p_a − p_b: the same equations, the same multipliers
            e = {"name": name, "type": "inline" if closes else "revolute", "a": b, "b": a,
                 "at": _xyz(pa), "axis": Z}
            info["forces"][name] = {f"{name}.{k}": f"{name}.{k}" for k in (0, 1)}
            if not closes:
                info["revolutes"][frozenset((a, b))] = e
                info["tree"][(a, b)] = e
            spatial[i] = e
        elif kind == "prismatic":
            if not j.get("lock_rotation", True):
                raise ValueError(f"{where}: a prismatic joint without lock_rotation has no spatial "
                                 "counterpart here")
            a, pa = _point(bodies, j.get("a"), where + "/a")
            if a == "ground":
                raise ValueError(f"{where}/a: expected a point on a body")
            x0 = j.get("through", pa)
            d = j["direction"]
            if not tree.join("ground", a):
                raise ValueError(f"{where}: this prismatic joint closes a loop; the converter "
                                 "closes loops with revolute joints only")
            # the body's point on the line through x0: the spatial joint sits at x0
            e = {"name": name, "type": "prismatic", "a": "ground", "b": a, "at": _xyz(x0),
                 "axis": _xyz(d)}
            info["prismatics"][a] = (e, d, x0, pa)
            side = _prismatic_side_equation(d)
            if side is not None:
                info["forces"][name] = {f"{name}.0": f"{name}.{side}"}
            info["tree"][("ground", a)] = e
            spatial[i] = e
        elif kind in ("rotation_driver", "translation_driver"):
            continue
        else:
            raise ValueError(f"{where}: a {kind} joint has no spatial counterpart here")
    out = [spatial[i] for i in sorted(spatial)]
    for i, j in enumerate(joints):
        where = f"/joints/{i}"
        if j.get("type") == "rotation_driver":
            out.append(_rotation_driver(j, i, where, bodies, info))
        elif j.get("type") == "translation_driver":
            out.append(_translation_driver(j, i, where, bodies, info))
    # a group of bodies without a joint to the ground moves in the plane
    for name in bodies.by_name:
        if tree.root(name) != tree.root("ground"):
            out.append({"name": f"{name}_in_plane", "type": "planar", "a": "ground", "b": name,
                        "at": _body(bodies.by_name[name])["position"], "normal": Z})
            info["tree"][("ground", name)] = out[-1]
            info.setdefault("planar_roots", set()).add(name)
            tree.join(name, "ground")
    info["parent"] = _parents(info["tree"])
    return out, info


def _prismatic_side_equation(d):
    """The index of a spatial prismatic joint's equation that is the planar one, n·(p − x0) = 0
    with n = (−d_y, d_x), with the same sign; None when it has the opposite sign. The spatial
    frame (docs/case-format.md): a3 = d, a1 the ground axis least aligned with it made
    perpendicular, a2 = a3 × a1; equations a1·b3, a2·b3, a1·gap, a2·gap, a1·b2."""
    n = math.hypot(d[0], d[1])
    a3 = [d[0] / n, d[1] / n, 0.0]
    k = min(range(3), key=lambda i: (abs(a3[i]), i))
    a1 = [(1.0 if i == k else 0.0) - a3[k] * a3[i] for i in range(3)]
    m = math.sqrt(sum(v * v for v in a1))
    a1 = [v / m for v in a1]
    a2 = [a3[1] * a1[2] - a3[2] * a1[1], a3[2] * a1[0] - a3[0] * a1[2],
          a3[0] * a1[1] - a3[1] * a1[0]]
    normal = [-a3[1], a3[0], 0.0]
    for index, a in ((2, a1), (3, a2)):
        c = sum(x * y for x, y in zip(normal, a))
        if abs(c - 1) < 1e-12:
            return index
    return None


def _pair(j, bodies):
    """The two bodies (or ground) a planar revolute joint connects, unordered."""
    try:
        a = _point(bodies, j.get("a"), "")[0]
        b = _point(bodies, j.get("b", "ground"), "", default_ground=[0, 0])[0]
    except (ValueError, KeyError, TypeError):
        return None
    return frozenset((a, b))


def _parents(tree_edges):
    """Each body's joint towards the ground along the tree: body → (parent, joint entry)."""
    adj = {}
    for (a, b), e in tree_edges.items():
        adj.setdefault(a, []).append((b, e))
        adj.setdefault(b, []).append((a, e))
    parent, todo = {}, ["ground"]
    seen = {"ground"}
    while todo:
        n = todo.pop()
        for m, e in adj.get(n, []):
            if m not in seen:
                seen.add(m)
                parent[m] = (n, e)
                todo.append(m)
    return parent


def _rotation_driver(j, i, where, bodies, info):
    body, rel = j["body"], j.get("relative_to", "ground")
    e = info["revolutes"].get(frozenset((body, rel)))
    if e is None:
        raise ValueError(f"{where}: the driver's bodies '{body}' and '{rel}' need a revolute joint "
                         "of the tree between them (the converter drives joint angles)")
    if (e["a"], e["b"]) != (rel, body):  # θ of the spatial joint: b relative to a
        e["a"], e["b"] = rel, body
        info["forces"].pop(e["name"], None)  # its multipliers change sign
    th0 = bodies.pose(body)[1] - (0.0 if rel == "ground" else bodies.pose(rel)[1])
    return {"name": j.get("name", f"rotation_driver_{i}"), "type": "rotation_driver",
            "joint": e["name"], "law": copy.deepcopy(j["law"]), "offset": th0}


def _translation_driver(j, i, where, bodies, info):
    b, p = _point(bodies, j.get("point"), where + "/point")
    if b not in info["prismatics"]:
        raise ValueError(f"{where}: the driven body '{b}' needs a prismatic joint to the ground")
    e, d, x0, _ = info["prismatics"][b]
    u = j.get("direction", d)
    if abs(u[0] * d[1] - u[1] * d[0]) > 1e-12 * math.hypot(*u) * math.hypot(*d):
        raise ValueError(f"{where}/direction: expected the direction of '{e['name']}'")
    through = j.get("through", p)
    n = math.hypot(*u)
    # planar: u·(p − x0) − s(t); spatial: a3·(x_b − x_a), zero at t = 0, a3 = d/|d|
    if u[0] * d[0] + u[1] * d[1] < 0 or abs(n - 1) > 1e-12:
        raise ValueError(f"{where}/direction: expected the unit vector along the prismatic "
                         f"joint's direction (the spatial driver acts along '{e['name']}')")
    offset = (p[0] - through[0]) * u[0] + (p[1] - through[1]) * u[1]
    law = copy.deepcopy(j["law"])
    return {"name": j.get("name", f"translation_driver_{i}"), "type": "translation_driver",
            "joint": e["name"], "law": law, "offset": offset}


def _forces(forces, bodies, info):
    out = []
    for i, f in enumerate(forces):
        where, kind = f"/forces/{i}", f.get("type")
        name = f.get("name", f"{kind}_{i}")
        if kind == "spring_damper":
            a, pa = _point(bodies, f["a"], where + "/a")
            b, pb = _point(bodies, f["b"], where + "/b")
            e = {"name": name, "type": "spring_damper", "a": a, "a_at": _xyz(pa), "b": b,
                 "b_at": _xyz(pb), "stiffness": f["stiffness"]}
            for k in ("damping", "free_length"):
                if k in f:
                    e[k] = f[k]
        elif kind == "torque":
            if f.get("body") not in bodies.by_name:
                raise ValueError(f"{where}/body: expected a rigid body")
            e = {"name": name, "type": "torque", "body": f["body"]}
            if "law" in f:
                e["tz"] = copy.deepcopy(f["law"])
            else:
                e["torque"] = [0.0, 0.0, float(f["torque"])]
        elif kind == "point_force":
            b, p = _point(bodies, f["point"], where + "/point")
            if b == "ground":
                raise ValueError(f"{where}/point: expected a point on a body")
            e = {"name": name, "type": "point_force", "body": b, "at": _xyz(p)}
            if "force" in f:
                e["force"] = _xyz(f["force"])
            for k in ("fx", "fy"):
                if k in f:
                    e[k] = copy.deepcopy(f[k])
        elif kind == "rotational_spring_damper":
            a, b = f["a"], f.get("b", "ground")
            j = info["revolutes"].get(frozenset((a, b)))
            if j is None:
                raise ValueError(f"{where}: '{a}' and '{b}' need a revolute joint of the tree "
                                 "between them (the converter puts the spring on its angle)")
            e = {"name": name, "type": "rotational_spring_damper", "joint": j["name"],
                 "stiffness": f["stiffness"]}
            if "damping" in f:
                e["damping"] = f["damping"]
            if "free_angle" in f:  # planar: θa − θb − θ0; spatial: θ_j from its assembly
                init = bodies.pose(a)[1] - (0.0 if b == "ground" else bodies.pose(b)[1])
                sign = 1.0 if (j["a"], j["b"]) == (b, a) else -1.0
                e["free_angle"] = sign * (float(f["free_angle"]) - init)
        else:
            raise ValueError(f"{where}: a {kind} force has no spatial counterpart here")
        if "scale" in f:
            e["scale"] = f["scale"]
        out.append(e)
    return out


def _angle_terms(body, info, where):
    """The joint angles whose sum, plus the initial angle, is the body's planar angle."""
    terms, n = [], body
    while n != "ground":
        parent, e = info["parent"][n]
        if e["type"] == "planar":
            raise ValueError(f"{where}: '{body}' has no revolute path to the ground, so its angle "
                             "is not a sum of joint angles")
        if e["type"] == "revolute":  # θ_e = Δ(angle of b − angle of a)
            terms.append((e["name"], 1.0 if e["b"] == n else -1.0))
        n = parent
    return terms


def _output(o, bodies, info, notes):
    out = {k: copy.deepcopy(v) for k, v in o.items() if k not in ("measures", "responses")}
    used = {r["measure"].split(".")[0] for r in o.get("responses", [])}
    for m in o.get("measures", []):
        if m.get("type") == "combination":
            used |= {t["measure"].split(".")[0] for t in m.get("terms", [])}
    measures, columns, angles = [], {}, {}
    names = {m.get("name") for m in o.get("measures", [])}
    for i, m in enumerate(o.get("measures", [])):
        where, kind, name = f"/output/measures/{i}", m.get("type"), m.get("name")
        if kind in ("position", "velocity"):
            b, p = _point(bodies, m["point"], where + "/point")
            if b == "ground":
                raise ValueError(f"{where}/point: expected a point on a body")
            measures.append({"name": name, "type": kind, "body": b, "at": _xyz(p)})
        elif kind == "angle":
            terms = []
            for joint, w in _angle_terms(m["body"], info, where):
                col = angles.get(joint)
                if col is None:
                    col = joint + "_angle"
                    while col in names:
                        col += "_"
                    names.add(col)
                    angles[joint] = col
                    measures.append({"name": col, "type": "joint_angle", "joint": joint})
                terms.append({"measure": col, "weight": w})
            measures.append({"name": name, "type": "combination", "terms": terms,
                             "constant": bodies.pose(m["body"])[1]})
        elif kind == "angular_velocity":
            measures.append({"name": name, "type": "angular_velocity", "body": m["body"]})
            columns[name] = name + ".z"
        elif kind == "constraint_force":
            joint = m.get("joint")
            mapped = info["forces"].get(joint)
            if mapped is None:
                if name in used:
                    raise ValueError(f"{where}: the multipliers of '{joint}' have no counterpart of "
                                     "the same sign among the spatial joint's, and a response uses "
                                     "them")
                notes.append(f"left out measure '{name}' (constraint_force of '{joint}')")
                continue
            measures.append({"name": name, "type": "constraint_force", "joint": joint})
            columns.update({c.replace(joint, name, 1): v.replace(joint, name, 1)
                            for c, v in mapped.items()})
        elif kind == "kinetic_energy":
            measures.append({"name": name, "type": "kinetic_energy"})
        elif kind == "combination":
            e = copy.deepcopy(m)
            for t in e["terms"]:
                t["measure"] = columns.get(t["measure"], t["measure"])
            measures.append(e)
        elif name in used:
            raise ValueError(f"{where}: a {kind} measure has no spatial counterpart here, and a "
                             "response uses it")
        else:
            notes.append(f"left out measure '{name}' ({kind}): no spatial counterpart here, and "
                         "no response uses it")
    out["measures"] = measures
    out["responses"] = []
    for r in o.get("responses", []):
        e = copy.deepcopy(r)
        e["measure"] = columns.get(e["measure"], e["measure"])
        out["responses"].append(e)
    return out


def _design(d, bodies):
    if "geometry" in d:
        raise ValueError("/design/geometry: level-set designs are planar (spatial cases refuse "
                         "them)")
    out = {k: copy.deepcopy(v) for k, v in d.items() if k != "parameters"}
    params = []
    for i, p in enumerate(d.get("parameters", [])):
        owner, _, what = p["parameter"].rpartition(".")
        if what == "inertia" and owner in bodies.by_name:
            for k in ("I1", "I2", "I3"):
                params.append(dict(copy.deepcopy(p), parameter=f"{owner}.{k}"))
        elif what in ("mass", "stiffness", "damping", "free_length", "scale"):
            params.append(copy.deepcopy(p))
        else:
            raise ValueError(f"/design/parameters/{i}/parameter: '{p['parameter']}' is not carried "
                             "over (masses, inertias, spring constants and load scales are)")
    out["parameters"] = params
    return out
