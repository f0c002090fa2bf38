"""A planar case written as a spatial one ("dimension": 3), all motion in the plane z = 0.

    doc3, notes = to_spatial(json.load(open("data/andrews/andrews_squeezer.json")))

The same mechanism, in natural coordinates (docs/methods.md, "Spatial rigid bodies"); its
responses and gradients agree with the planar case's to the integrator's O(h²), not to
round-off. Pure Python on the JSON documents (scripts/planar_to_spatial.py, its command line,
needs no compiled module). docs/case-format.md, "Planar cases as spatial ones", says how each
planar kind is written.

Anything without a spatial counterpart here (flexible bodies, point masses, pressure loads, a
loop closed by a prismatic joint, a case that is not assembled at t = 0, …) raises ValueError
naming its JSON path; measures no response uses are left out with a note instead.
"""
import copy
import math
import os

Z = [0.0, 0.0, 1.0]

# The planar keys the converter reads, per kind (keys starting with "_" are comments, as in the
# loader); any other key is refused, as the planar loader refuses it.
_COMMON = {"name", "type", "comment", "description"}
_KEYS = {
    "body": _COMMON | {"position", "angle", "mass", "inertia", "com", "velocity",
                       "angular_velocity"},
    "revolute": _COMMON | {"a", "b"},
    "prismatic": _COMMON | {"a", "direction", "through", "lock_rotation"},
    "rotation_driver": _COMMON | {"body", "relative_to", "law"},
    "translation_driver": _COMMON | {"point", "direction", "through", "law"},
    "spring_damper": _COMMON | {"a", "b", "stiffness", "damping", "free_length"},
    "torque": _COMMON | {"body", "torque", "law", "scale"},
    "point_force": _COMMON | {"point", "force", "fx", "fy", "scale"},
    "rotational_spring_damper": _COMMON | {"a", "b", "stiffness", "damping", "free_angle"},
    "position": _COMMON | {"point"},
    "velocity": _COMMON | {"point"},
    "angle": _COMMON | {"body"},
    "angular_velocity": _COMMON | {"body"},
    "kinetic_energy": _COMMON,
    "combination": _COMMON | {"terms", "constant"},
    "constraint_force": _COMMON | {"joint"},
}


def _check_keys(entry, where, kind):
    if not isinstance(entry, dict):
        raise ValueError(f"{where}: expected an object")
    for k in entry:
        if k not in _KEYS[kind] and not k.startswith("_"):
            raise ValueError(f"{where}/{k}: unknown key (check the spelling; the planar loader "
                             "refuses it too)")


def _req(entry, key, where):
    if key not in entry:
        raise ValueError(f"{where}: missing required key '{key}'")
    return entry[key]


def _num(v, where):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ValueError(f"{where}: expected a number, got {json_text(v)}")
    return float(v)


def _vec2(v, where):
    if not isinstance(v, list) or len(v) != 2:
        raise ValueError(f"{where}: expected [x, y], got {json_text(v)}")
    return [_num(v[0], where + "/0"), _num(v[1], where + "/1")]


def _direction(v, where):
    d = _vec2(v, where)
    n = math.hypot(*d)
    if not n > 0:
        raise ValueError(f"{where}: expected a non-zero direction")
    return [d[0] / n, d[1] / n]


def json_text(v):
    s = repr(v)
    return s if len(s) < 60 else s[:57] + "..."


def _xyz(p):
    return [float(p[0]), float(p[1]), 0.0]


class _Bodies:
    """The planar rigid bodies by name: reference point, angle, centre-of-mass offset."""

    def __init__(self, bodies):
        if not isinstance(bodies, list):
            raise ValueError("/bodies: expected an array")
        self.by_name, self.where = {}, {}
        for i, b in enumerate(bodies):
            where = f"/bodies/{i}"
            if not isinstance(b, dict):
                raise ValueError(f"{where}: expected an object")
            if b.get("type", "rigid") != "rigid":
                raise ValueError(f"{where}: a {b.get('type')} body has no spatial counterpart here "
                                 "(spatial cases hold rigid bodies only)")
            _check_keys(b, where, "body")
            name = _req(b, "name", where)
            for k in ("position", "com", "velocity"):
                if k in b:
                    _vec2(b[k], f"{where}/{k}")
            for k in ("angle", "mass", "inertia", "angular_velocity"):
                if k in b:
                    _num(b[k], f"{where}/{k}")
            self.by_name[name], self.where[name] = b, where

    def pose(self, name):
        b = self.by_name[name]
        return b.get("position", [0.0, 0.0]), float(b.get("angle", 0.0))

    def world(self, name, at):
        (px, py), th = self.pose(name)
        c, s = math.cos(th), math.sin(th)
        return [px + c * at[0] - s * at[1], py + s * at[0] + c * at[1]]

    def angle(self, name):
        return 0.0 if name == "ground" else self.pose(name)[1]

    def size(self):
        pts = [self.pose(n)[0] for n in self.by_name] or [[0.0, 0.0]]
        return max(1.0, max(abs(v) for p in pts for v in p))


def _point(bodies, p, where, default_ground=None):
    """A planar point as (body or "ground", [x, y] at t = 0)."""
    if p == "ground":
        if default_ground is None:
            raise ValueError(f"{where}: \"ground\" without a point")
        return "ground", list(default_ground)
    if isinstance(p, dict) and "ground" in p:
        return "ground", _vec2(p["ground"], where + "/ground")
    if isinstance(p, dict) and "body" in p:
        if p["body"] not in bodies.by_name:
            raise ValueError(f"{where}/body: '{p['body']}' is not a rigid body of the case")
        if "node" in p or "nearest" in p:
            raise ValueError(f"{where}: a node of a flexible body has no spatial counterpart here")
        if "at_global" in p:
            return p["body"], _vec2(p["at_global"], where + "/at_global")
        return p["body"], bodies.world(p["body"], _vec2(p.get("at", [0.0, 0.0]), where + "/at"))
    raise ValueError(f"{where}: expected a point ({{\"body\", \"at\"}} or {{\"ground\": [x, y]}})")


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


def to_spatial(doc, source="the planar case", src_dir=None, out_dir=None):
    """The spatial document of a planar case document, and notes on what was left out. With
    src_dir and out_dir, relative table files are rewritten relative to out_dir."""
    if not isinstance(doc, dict):
        raise ValueError("/: expected a case object")
    if doc.get("dimension", 2) != 2:
        raise ValueError("/dimension: expected a planar case (dimension 2)")
    for key in ("initial_state",):
        if key in doc:
            raise ValueError(f"/{key}: not carried over (spatial cases do not take it)")
    bodies = _Bodies(doc.get("bodies", []))
    out = {k: copy.deepcopy(v) for k, v in doc.items()
           if k not in ("bodies", "joints", "forces", "output", "design", "gravity", "conditions")}
    out["name"] = str(doc.get("name", "case")) + "_spatial"
    out["description"] = (f"{source} written as a spatial case by scripts/planar_to_spatial.py "
                          "(all motion in z = 0). " + str(doc.get("description", "")))
    out["dimension"] = 3
    out["gravity"] = _xyz(_vec2(doc.get("gravity", [0.0, 0.0]), "/gravity"))
    notes = []
    out["bodies"] = [_body(b, bodies.where[b["name"]]) for b in doc.get("bodies", [])]
    joints = doc.get("joints", [])
    forces = doc.get("forces", [])
    for name, lst in (("joints", joints), ("forces", forces)):
        if not isinstance(lst, list) or not all(isinstance(e, dict) for e in lst):
            raise ValueError(f"/{name}: expected an array of objects")
    joints3, info = _joints(joints, forces, bodies)
    out["joints"] = joints3
    out["forces"] = _forces(forces, bodies, info)
    if "output" in doc:
        out["output"] = _output(doc["output"], bodies, info, notes)
    if "design" in doc:
        out["design"] = _design(doc["design"], bodies)
    if "conditions" in doc:
        out["conditions"] = _conditions(doc["conditions"], doc, info)
    _velocity_note(doc, bodies, notes)
    if src_dir is not None and out_dir is not None:
        _rewrite_files(out, src_dir, out_dir)
    return out, notes


def _body(b, where):
    (px, py), th = b.get("position", [0.0, 0.0]), float(b.get("angle", 0.0))
    c, s = math.cos(th), math.sin(th)
    cx, cy = b.get("com", [0.0, 0.0])
    com = [px + c * cx - s * cy, py + s * cx + c * cy]
    J = float(b.get("inertia", 0.0))
    o = {"name": b["name"], "type": "rigid", "mass": float(b.get("mass", 0.0)), "inertia": [J, J, J],
         "position": _xyz(com), "orientation": {"axis": Z, "angle": th}}
    if "comment" in b:
        o["comment"] = b["comment"]
    if "angular_velocity" in b:
        o["angular_velocity"] = [0.0, 0.0, float(b["angular_velocity"])]
    if "velocity" in b:  # of the reference point; spatial: of the centre of mass
        rx, ry = com[0] - px, com[1] - py
        if "angular_velocity" not in b and (rx or ry):
            raise ValueError(f"{where}/velocity: the spatial velocity is the centre of mass's, "
                             "which needs the angular velocity too (the centre of mass is off the "
                             "reference point): give angular_velocity")
        w = float(b.get("angular_velocity", 0.0))
        vx, vy = b["velocity"]
        o["velocity"] = [vx - w * ry, vy + w * rx, 0.0]
    return o


def _velocity_note(doc, bodies, notes):
    open_ = [n for n, b in bodies.by_name.items()
             if "velocity" not in b or "angular_velocity" not in b]
    moving = any("velocity" in b or "angular_velocity" in b for b in bodies.by_name.values()) or \
        any(j.get("type", "").endswith("_driver") for j in doc.get("joints", []))
    if open_ and moving:
        notes.append("the velocities at t = 0 of " + ", ".join(f"'{n}'" for n in open_) +
                     " are not given: where the joints and drivers leave them open, the spatial "
                     "projection fills them differently from the planar one (give velocity and "
                     "angular_velocity for the same start)")


def _joints(joints, forces, bodies):
    """The spatial joints, and per planar joint what it became (for drivers and measures)."""
    tree = _Tree()
    tol = 1e-9 * bodies.size()
    angled = set()  # the body pairs whose revolute joint must carry an angle: driven or sprung
    tdirs = {}  # body → the direction of a translation driver on it
    for i, j in enumerate(joints):
        kind, where = j.get("type"), f"/joints/{i}"
        if kind not in ("revolute", "prismatic", "rotation_driver", "translation_driver"):
            if kind in ("rigid_connection", "clamp"):
                raise ValueError(f"{where}: a {kind} joint holds a flexible body, which has no "
                                 "spatial counterpart here")
            raise ValueError(f"{where}: a {kind} joint has no spatial counterpart here")
        _check_keys(j, where, kind)
        if kind == "rotation_driver":
            angled.add(frozenset((_req(j, "body", where), j.get("relative_to", "ground"))))
        if kind == "translation_driver":
            b, _ = _point(bodies, _req(j, "point", where), where + "/point")
            tdirs[b] = _direction(_req(j, "direction", where), where + "/direction")
    for f in forces:
        if f.get("type") == "rotational_spring_damper":
            angled.add(frozenset((f.get("a"), f.get("b", "ground"))))

    def rank(i):
        kind = joints[i].get("type")
        if kind == "prismatic":
            return 0
        return 1 if kind == "revolute" and _pair(joints[i], bodies) in angled else 2

    order = sorted(range(len(joints)), key=lambda i: (rank(i), i))
    info = {"revolutes": {}, "closing": {}, "prismatics": {}, "tree": {}, "forces": {},
            "names": {}}
    spatial = {}
    for i in order:
        j, where = joints[i], f"/joints/{i}"
        kind = j.get("type")
        name = j.get("name", f"{kind}_{i}")
        info["names"][i] = name
        if kind == "revolute":
            a, pa = _point(bodies, _req(j, "a", where), where + "/a")
            b, pb = _point(bodies, j.get("b", "ground"), where + "/b", default_ground=pa)
            if math.dist(pa, pb) > tol:
                raise ValueError(f"{where}: not assembled at t = 0: a at {pa} and b at {pb} are "
                                 f"{math.dist(pa, pb):.3g} m apart (the planar run projects the "
                                 "bodies onto the joints, the converter does not): place the "
                                 "bodies where the joints hold them")
            if a == b:
                raise ValueError(f"{where}: a joint cannot connect a body to itself")
            closes = not tree.join(a, b)
            # spatial x_b − x_a = planar p_a − p_b: the same equations, the same multipliers
            e = {"name": name, "type": "inline" if closes else "revolute", "a": b, "b": a,
                 "at": _xyz(pa), "axis": Z}
            if closes:
                info["closing"][frozenset((a, b))] = e
                if b == "ground":  # the inline joint's frame turns with a: ground components
                    info["forces"][name] = {f"{name}.{k}": f"{name}.{k}" for k in (0, 1)}
            else:
                info["revolutes"][frozenset((a, b))] = e
                info["tree"][(a, b)] = e
                info["forces"][name] = {f"{name}.{k}": f"{name}.{k}" for k in (0, 1)}
            spatial[i] = e
        elif kind == "prismatic":
            spatial[i] = _prismatic(j, i, where, name, bodies, tree, tdirs, info, tol)
        else:
            continue
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
                        "at": _body(bodies.by_name[name], "")["position"], "normal": Z})
            info["tree"][("ground", name)] = out[-1]
            tree.join(name, "ground")
    info["parent"] = _parents(info["tree"])
    return out, info


def _prismatic(j, i, where, name, bodies, tree, tdirs, info, tol):
    if not j.get("lock_rotation", True):
        raise ValueError(f"{where}: a prismatic joint without lock_rotation has no spatial "
                         "counterpart here")
    a, pa = _point(bodies, _req(j, "a", where), where + "/a")
    if a == "ground":
        raise ValueError(f"{where}/a: expected a point on a body")
    d = _direction(_req(j, "direction", where), where + "/direction")
    x0 = _vec2(j["through"], where + "/through") if "through" in j else pa
    off = -d[1] * (pa[0] - x0[0]) + d[0] * (pa[1] - x0[1])
    if abs(off) > tol:
        raise ValueError(f"{where}: not assembled at t = 0: the point a is {off:.3g} m off the "
                         "line (the planar run projects it, the converter does not): place the "
                         "body on the line")
    if not tree.join("ground", a):
        raise ValueError(f"{where}: this prismatic joint closes a loop; the converter closes "
                         "loops with revolute joints only (list a revolute of the loop later)")
    # the axis: a translation driver's direction (its s(t) is along it), else d or −d, whichever
    # makes the planar side equation n·(p − x0), n = (−d_y, d_x), a spatial one of the same sign
    n_planar = [-d[1], d[0]]

    def same_sign(ax):
        index, a = _prismatic_side_equation(ax)
        return index if a[0] * n_planar[0] + a[1] * n_planar[1] > 0 else None

    axis = tdirs.get(a)
    if axis is None:
        axis = d if same_sign(d) is not None else [-d[0], -d[1]]
    index = same_sign(axis)
    e = {"name": name, "type": "prismatic", "a": "ground", "b": a, "at": _xyz(pa),
         "axis": _xyz(axis)}
    info["prismatics"][a] = (e, axis)
    info["tree"][("ground", a)] = e
    info["forces"][name] = {f"{name}.0": f"{name}.{index}"} if index is not None else {}
    return e


def _prismatic_side_equation(d):
    """The spatial prismatic joint of axis d: the index of its equation along the in-plane
    normal, and that equation's vector (a1 or a2). The spatial frame (docs/case-format.md):
    a3 = d, a1 the ground axis least aligned with it made perpendicular, a2 = a3 × a1; equations
    a1·b3, a2·b3, a1·gap, a2·gap, a1·b2."""
    a3 = [d[0], d[1], 0.0]
    k = min(range(3), key=lambda i: (abs(a3[i]), i))
    a1 = [(1.0 if i == k else 0.0) - a3[k] * a3[i] for i in range(3)]
    m = math.sqrt(sum(v * v for v in a1))
    a1 = [v / m for v in a1]
    a2 = [a3[1] * a1[2] - a3[2] * a1[1], a3[2] * a1[0] - a3[0] * a1[2],
          a3[0] * a1[1] - a3[1] * a1[0]]
    return (2, a1) if abs(a1[2]) < 0.5 else (3, a2)


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


def _tree_revolute(info, a, b, where, what):
    """The revolute of the tree between a and b, or a ValueError that says why there is none."""
    e = info["revolutes"].get(frozenset((a, b)))
    if e is not None:
        return e
    closing = info["closing"].get(frozenset((a, b)))
    if closing is not None:
        raise ValueError(f"{where}: {what} needs the angle of the revolute '{closing['name']}', "
                         "which closes a loop and is written as an inline joint (no angle): at "
                         "most all but one revolute of a loop can carry drivers and rotational "
                         "springs")
    raise ValueError(f"{where}: {what} needs a revolute joint between '{a}' and '{b}' (the "
                     "converter drives and springs joint angles)")


def _rotation_driver(j, i, where, bodies, info):
    body, rel = j["body"], j.get("relative_to", "ground")
    for n, key in ((body, "body"), (rel, "relative_to")):
        if n != "ground" and n not in bodies.by_name:
            raise ValueError(f"{where}/{key}: '{n}' is not a rigid body of the case")
    e = _tree_revolute(info, body, rel, where, "the driver")
    if (e["a"], e["b"]) != (rel, body):  # θ of the spatial joint: b relative to a
        e["a"], e["b"] = rel, body
        info["forces"].pop(e["name"], None)  # its multipliers change sign
    th0 = bodies.angle(body) - bodies.angle(rel)
    return {"name": j.get("name", f"rotation_driver_{i}"), "type": "rotation_driver",
            "joint": e["name"], "law": copy.deepcopy(_req(j, "law", where)), "offset": th0}


def _translation_driver(j, i, where, bodies, info):
    b, p = _point(bodies, j["point"], where + "/point")
    if b not in info["prismatics"]:
        raise ValueError(f"{where}: the driven body '{b}' needs a prismatic joint to the ground")
    e, axis = info["prismatics"][b]
    u = _direction(j["direction"], where + "/direction")
    if abs(u[0] * axis[1] - u[1] * axis[0]) > 1e-12:
        raise ValueError(f"{where}/direction: expected the direction of '{e['name']}' (the "
                         "spatial driver acts along its axis)")
    through = _vec2(j["through"], where + "/through") if "through" in j else p
    # planar: û·(p − x0) − s(t); spatial: a3·(x_b − x_a), zero at t = 0, a3 = û
    offset = (p[0] - through[0]) * u[0] + (p[1] - through[1]) * u[1]
    return {"name": j.get("name", f"translation_driver_{i}"), "type": "translation_driver",
            "joint": e["name"], "law": copy.deepcopy(_req(j, "law", where)), "offset": offset}


def _forces(forces, bodies, info):
    out = []
    for i, f in enumerate(forces):
        where, kind = f"/forces/{i}", f.get("type")
        if kind not in ("spring_damper", "torque", "point_force", "rotational_spring_damper"):
            raise ValueError(f"{where}: a {kind} force has no spatial counterpart here")
        _check_keys(f, where, kind)
        name = f.get("name", f"{kind}_{i}")
        if kind == "spring_damper":
            a, pa = _point(bodies, _req(f, "a", where), where + "/a")
            b, pb = _point(bodies, _req(f, "b", where), where + "/b")
            e = {"name": name, "type": "spring_damper", "a": a, "a_at": _xyz(pa), "b": b,
                 "b_at": _xyz(pb), "stiffness": _req(f, "stiffness", where)}
            for k in ("damping", "free_length"):
                if k in f:
                    e[k] = f[k]
        elif kind == "torque":
            body = _req(f, "body", where)
            if body not in bodies.by_name:
                raise ValueError(f"{where}/body: '{body}' is not a rigid body of the case")
            e = {"name": name, "type": "torque", "body": body}
            if "law" in f:
                e["tz"] = copy.deepcopy(f["law"])
            else:
                e["torque"] = [0.0, 0.0, _num(_req(f, "torque", where), where + "/torque")]
        elif kind == "point_force":
            b, p = _point(bodies, _req(f, "point", where), where + "/point")
            if b == "ground":
                raise ValueError(f"{where}/point: expected a point on a body")
            e = {"name": name, "type": "point_force", "body": b, "at": _xyz(p)}
            if "force" in f:
                e["force"] = _xyz(_vec2(f["force"], where + "/force"))
            for k in ("fx", "fy"):
                if k in f:
                    e[k] = copy.deepcopy(f[k])
        else:
            a, b = _req(f, "a", where), f.get("b", "ground")
            for n, key in ((a, "a"), (b, "b")):
                if n != "ground" and n not in bodies.by_name:
                    raise ValueError(f"{where}/{key}: '{n}' is not a rigid body of the case")
            j = _tree_revolute(info, a, b, where, "the rotational spring")
            e = {"name": name, "type": "rotational_spring_damper", "joint": j["name"],
                 "stiffness": _req(f, "stiffness", where)}
            if "damping" in f:
                e["damping"] = f["damping"]
            if "free_angle" in f:  # planar: θa − θb − θ0; spatial: θ_j from its assembly
                init = bodies.angle(a) - bodies.angle(b)
                sign = 1.0 if (j["a"], j["b"]) == (b, a) else -1.0
                e["free_angle"] = sign * (_num(f["free_angle"], where + "/free_angle") - init)
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
    if not isinstance(o, dict):
        raise ValueError("/output: expected an object")
    out = {k: copy.deepcopy(v) for k, v in o.items() if k not in ("measures", "responses")}
    measures_in, responses_in = o.get("measures", []), o.get("responses", [])
    for i, r in enumerate(responses_in):
        if not isinstance(r, dict) or not isinstance(r.get("measure"), str):
            raise ValueError(f"/output/responses/{i}/measure: expected a measure column name")
    used = {r["measure"].split(".")[0] for r in responses_in}
    for m in measures_in:
        if isinstance(m, dict) and m.get("type") == "combination":
            used |= {str(t.get("measure", "")).split(".")[0] for t in m.get("terms", [])
                     if isinstance(t, dict)}
    measures, columns, angles, forces = [], {}, {}, {}
    names = {m.get("name") for m in measures_in if isinstance(m, dict)}
    for i, m in enumerate(measures_in):
        where = f"/output/measures/{i}"
        if not isinstance(m, dict):
            raise ValueError(f"{where}: expected an object")
        kind, name = m.get("type"), _req(m, "name", where)
        if kind not in _KEYS:
            if name in used:
                raise ValueError(f"{where}: a {kind} measure has no spatial counterpart here, and "
                                 "a response uses it")
            notes.append(f"left out measure '{name}' ({kind}): no spatial counterpart here, and "
                         "no response uses it")
            continue
        _check_keys(m, where, kind)
        if kind in ("position", "velocity"):
            b, p = _point(bodies, _req(m, "point", where), where + "/point")
            if b == "ground":
                raise ValueError(f"{where}/point: expected a point on a body")
            measures.append({"name": name, "type": kind, "body": b, "at": _xyz(p)})
        elif kind == "angle":
            terms = []
            for joint, w in _angle_terms(_req(m, "body", where), info, where):
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
                             "constant": bodies.angle(m["body"])})
        elif kind == "angular_velocity":
            if m.get("body") not in bodies.by_name:
                raise ValueError(f"{where}/body: expected a rigid body of the case")
            measures.append({"name": name, "type": "angular_velocity", "body": m["body"]})
            columns[name] = name + ".z"
        elif kind == "kinetic_energy":
            measures.append({"name": name, "type": "kinetic_energy"})
        elif kind == "combination":
            e = copy.deepcopy(m)
            for t in e.get("terms", []):
                col = t.get("measure")
                _mapped(col, columns, forces, f"{where}/terms")
                t["measure"] = columns.get(col, col)
            measures.append(e)
        else:  # constraint_force
            joint = _req(m, "joint", where)
            measures.append({"name": name, "type": "constraint_force", "joint": joint})
            mapped = info["forces"].get(joint, {})
            forces[name] = joint
            columns.update({c.replace(joint, name, 1): v.replace(joint, name, 1)
                            for c, v in mapped.items()})
    out["measures"] = measures
    out["responses"] = []
    for i, r in enumerate(responses_in):
        e = copy.deepcopy(r)
        _mapped(e["measure"], columns, forces, f"/output/responses/{i}/measure")
        e["measure"] = columns.get(e["measure"], e["measure"])
        out["responses"].append(e)
    return out


def _mapped(col, columns, forces, where):
    """Refuses a constraint-force column without a spatial equation of the same meaning."""
    base = str(col).split(".")[0]
    if base in forces and col not in columns:
        raise ValueError(f"{where}: '{col}' has no spatial equation of the same sign and frame "
                         f"(the joint '{forces[base]}': a revolute's x and y, an inline joint to "
                         "the ground, a prismatic joint's side force keep theirs)")


def _design(d, bodies):
    if not isinstance(d, dict):
        raise ValueError("/design: expected an object")
    if "geometry" in d:
        raise ValueError("/design/geometry: level-set designs are planar (spatial cases refuse "
                         "them)")
    out = {k: copy.deepcopy(v) for k, v in d.items() if k != "parameters"}
    params = []
    for i, p in enumerate(d.get("parameters", [])):
        where = f"/design/parameters/{i}/parameter"
        owner, _, what = str(_req(p, "parameter", where)).rpartition(".")
        if what == "inertia" and owner in bodies.by_name:
            for k in ("I1", "I2", "I3"):
                params.append(dict(copy.deepcopy(p), parameter=f"{owner}.{k}"))
        elif what in ("mass", "stiffness", "damping", "free_length", "scale"):
            params.append(copy.deepcopy(p))
        else:
            raise ValueError(f"{where}: '{p['parameter']}' is not carried over (masses, "
                             "inertias, spring constants and load scales are)")
    out["parameters"] = params
    return out


def _conditions(conditions, doc, info):
    """Conditions whose pointers mean the same in the spatial document: simulation options,
    spring constants, load scales and masses by name, driver laws."""
    if not isinstance(conditions, list):
        raise ValueError("/conditions: expected an array")
    named = {"bodies": [b.get("name") for b in doc.get("bodies", [])],
             "joints": [info["names"].get(i, j.get("name")) for i, j in
                        enumerate(doc.get("joints", []))],
             "forces": [f.get("name", f"{f.get('type')}_{i}") for i, f in
                        enumerate(doc.get("forces", []))]}
    kinds = {f.get("name"): f.get("type") for f in doc.get("forces", [])}
    jkinds = {j.get("name"): j.get("type") for j in doc.get("joints", [])}
    out = []
    for ci, c in enumerate(conditions):
        where = f"/conditions/{ci}"
        if not isinstance(c, dict):
            raise ValueError(f"{where}: expected an object")
        e = {k: copy.deepcopy(v) for k, v in c.items() if k != "set"}
        e["set"] = {}
        for ptr, value in (c.get("set") or {}).items():
            parts = str(ptr).strip("/").split("/")
            section = parts[0]
            if section in named and len(parts) >= 3:
                ref = parts[1]
                if ref.isdigit() and int(ref) < len(named[section]):
                    ref = named[section][int(ref)]
                key = "/".join(parts[2:])
                ok = (section == "forces" and kinds.get(ref) in ("spring_damper", "torque",
                      "point_force", "rotational_spring_damper") and
                      key in ("stiffness", "damping", "free_length", "scale")) or \
                     (section == "bodies" and key == "mass") or \
                     (section == "joints" and jkinds.get(ref, "").endswith("_driver") and
                      key == "law")
                if ok:
                    e["set"][f"/{section}/{ref}/{key}"] = copy.deepcopy(value)
                    continue
            elif section == "simulation":
                e["set"][ptr] = copy.deepcopy(value)
                continue
            raise ValueError(f"{where}/set/{ptr}: not carried over (a condition may set "
                             "simulation options, spring constants, load scales, masses and "
                             "driver laws here)")
        out.append(e)
    return out


def _rewrite_files(node, src_dir, out_dir):
    """Table files named relative to the planar case, named relative to the spatial one."""
    if isinstance(node, dict):
        f = node.get("file")
        if node.get("type") == "table" and isinstance(f, str) and not os.path.isabs(f):
            node["file"] = os.path.relpath(os.path.join(src_dir, f), out_dir)
        for v in node.values():
            _rewrite_files(v, src_dir, out_dir)
    elif isinstance(node, list):
        for v in node:
            _rewrite_files(v, src_dir, out_dir)
