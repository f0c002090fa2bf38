"""Models built in Python: bodies, joints, forces, meshes, features, design variables, responses.

    import lsmbs
    from lsmbs import at, ground, trapezoid

    m = lsmbs.ModelBuilder("pendulum", gravity=(0, -9.81))
    m.rigid_body("bob", position=(1, 0), mass=1, inertia=0.1)
    m.revolute("pin", at("bob", (-1, 0)))           # b defaults to the ground
    m.measure("bob", "position", point=at("bob"))
    m.response("lowest_y", "bob.y", "min")
    m.simulation(t_end=2, h=0.01)
    case = m.build()                                 # an lsmbs.Case, as load_case returns

The builder speaks the case format's vocabulary (docs/case-format.md) with Python names and
keyword arguments; `build()` hands its document to the same loader that reads case files, so a
model built here is checked exactly as a case file is (every range, reference, node set, the rank
of the constraints, the initial velocities), and `save(path)` writes a case file that the command
line runs to the same numbers, bit for bit. Mistakes the builder can see alone (a name taken
twice, a wrong type, a point that is not a point) raise at the call; the rest raise lsmbs.Error
at build() naming the call that made the entry, e.g.
    rigid_body('bob'): mass: expected a non-negative number
with the entry's JSON path in `json_path`. A builder can be changed and built again (a parameter
study rebuilds it); each build() returns a new, independent Case.
"""
from __future__ import annotations

import collections.abc
import copy
import json
import math
import numbers
import operator
import os
import pathlib

from . import _lsmbs

__all__ = [
    "ModelBuilder", "SpatialModelBuilder", "Variable", "ground", "at", "at_global", "node", "nearest", "rectangle",
    "gmsh", "trapezoid", "ramp", "constant", "table", "ellipse", "super_ellipse", "circle",
    "bspline",
]


# ---------------------------------------------------------------- values
def _number(value, what):
    if isinstance(value, Variable):
        raise TypeError(f"{what}: a design variable acts on a model parameter through "
                        f"bind_parameter('<entity>.<property>', {value.name!r}), or on a feature")
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{what}: expected a number, got {type(value).__name__}")
    if not math.isfinite(value):
        raise ValueError(f"{what}: expected a finite number, got {value}")
    return float(value)


def _integer(value, what):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{what}: expected an integer, got {type(value).__name__}")
    return int(value)


def _vec2(value, what):
    if (isinstance(value, (str, bytes, collections.abc.Mapping)) or not hasattr(value, "__len__")
            or len(value) != 2):
        raise TypeError(f"{what}: expected a pair (x, y), got {value!r}")
    return [_number(value[0], what + "[0]"), _number(value[1], what + "[1]")]


def _vec3(value, what):
    if (isinstance(value, (str, bytes, collections.abc.Mapping)) or not hasattr(value, "__len__")
            or len(value) != 3):
        raise TypeError(f"{what}: expected a triple (x, y, z), got {value!r}")
    return [_number(value[i], f"{what}[{i}]") for i in range(3)]


def _name(value, what):
    if not isinstance(value, str) or not value:
        raise TypeError(f"{what}: expected a non-empty str, got {value!r}")
    return value


def _plain(value, what):
    """A JSON value from Python: numbers (NumPy's too), str, bool, None, lists and dicts."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, (numbers.Real, Variable)):
        return _number(value, what)
    if isinstance(value, dict):
        return {_name(k, what): _plain(v, f"{what}.{k}") for k, v in value.items()}
    if hasattr(value, "tolist"):  # NumPy arrays
        return _plain(value.tolist(), what)
    if isinstance(value, (list, tuple)):
        return [_plain(v, f"{what}[{i}]") for i, v in enumerate(value)]
    raise TypeError(f"{what}: {type(value).__name__} is not a case value")


class _Point(dict):
    """A material point (a dict in the case format's form); made by ground, at, node, … ."""


def ground(xy):
    """The fixed point at xy."""
    return _Point(ground=_vec2(xy, "ground"))


def at(body, xy=(0.0, 0.0)):
    """The point of rigid body `body` at xy in its body frame."""
    return _Point(body=_name(body, "at: body"), at=_vec2(xy, "at"))


def at_global(body, xy):
    """The point of rigid body `body` that is at xy at t = 0."""
    return _Point(body=_name(body, "at_global: body"), at_global=_vec2(xy, "at_global"))


def node(body, index):
    """Node `index` of flexible body `body`."""
    return _Point(body=_name(body, "node: body"), node=_integer(index, "node"))


def nearest(body, xy):
    """The node of flexible body `body` nearest to xy (mesh frame)."""
    return _Point(body=_name(body, "nearest: body"), nearest=_vec2(xy, "nearest"))


def _point(p, what, allow_ground_word=False):
    if allow_ground_word and p == "ground":
        return "ground"
    if not isinstance(p, _Point):
        raise TypeError(f"{what}: expected a point (lsmbs.ground, at, at_global, node, nearest), "
                        f"got {p!r}")
    return dict(p)


# ---------------------------------------------------------------- meshes
def rectangle(origin, size, elements, node_sets=None, cells="quad4"):
    """A structured mesh of the rectangle [origin, origin + size], elements = (nx, ny): nx × ny
    quadrilaterals (cells="quad4") or each split into two triangles (cells="tri3"); node sets
    'left', 'right', 'bottom' and 'top' are predefined, `node_sets` adds selectors
    ({'tip': {'line_x': 0.8}}, docs/case-format.md)."""
    nx, ny = elements
    m = {"type": "rectangle", "origin": _vec2(origin, "rectangle: origin"),
         "size": _vec2(size, "rectangle: size"),
         "elements": [_integer(nx, "rectangle: elements[0]"), _integer(ny, "rectangle: elements[1]")]}
    if cells != "quad4":
        m["cells"] = cells  # checked by the loader, with the other values
    return _Mesh(m, node_sets)


def gmsh(file, scale=1.0, node_sets=None):
    """A Gmsh 4.x ASCII mesh of quadrilaterals and/or 3-node triangles; physical groups of
    dimension 0 and 1 become node sets."""
    m = {"type": "gmsh", "file": os.fspath(file), "scale": _number(scale, "gmsh: scale")}
    return _Mesh(m, node_sets)


class _Mesh:
    def __init__(self, mesh, node_sets):
        self.mesh = mesh
        self.node_sets = _plain(node_sets, "node_sets") if node_sets else None


# ---------------------------------------------------------------- time laws
def trapezoid(s0, s1, acceleration, speed, start=0.0):
    """From s0 to s1 with a trapezoidal speed profile (phases accelerate, constant, decelerate)."""
    return {"type": "trapezoid", "from": _number(s0, "trapezoid: s0"),
            "to": _number(s1, "trapezoid: s1"),
            "acceleration": _number(acceleration, "trapezoid: acceleration"),
            "speed": _number(speed, "trapezoid: speed"), "start": _number(start, "trapezoid: start")}


def ramp(speed, ramp_time, s0=0.0, start=0.0):
    """From s0, the speed ramped up over ramp_time, then constant (phases ramp, constant)."""
    return {"type": "ramp", "from": _number(s0, "ramp: s0"), "speed": _number(speed, "ramp: speed"),
            "ramp_time": _number(ramp_time, "ramp: ramp_time"), "start": _number(start, "ramp: start")}


def constant(value):
    return {"type": "constant", "value": _number(value, "constant: value")}


def table(points=None, file=None, interpolation="cubic", period=None, x_scale=None, y_scale=None):
    """A tabulated law s(t) or pressure P(s): points [(x, y), ...] or a CSV file."""
    t = {"type": "table", "interpolation": interpolation}
    if points is not None:
        t["points"] = [_vec2(p, f"table: points[{i}]") for i, p in enumerate(points)]
    if file is not None:
        t["file"] = os.fspath(file)
    for k, v in (("period", period), ("x_scale", x_scale), ("y_scale", y_scale)):
        if v is not None:
            t[k] = _number(v, "table: " + k)
    return t


# ---------------------------------------------------------------- design
class Variable:
    """A design variable; `scale * v + offset` binds a feature or model parameter linearly."""

    def __init__(self, name, scale=1.0, offset=0.0):
        self.name, self.scale, self.offset = name, scale, offset

    def __mul__(self, k):
        return Variable(self.name, self.scale * _number(k, self.name + " * k"),
                        self.offset * float(k))

    __rmul__ = __mul__

    def __neg__(self):
        return self * -1.0

    def __add__(self, c):
        return Variable(self.name, self.scale, self.offset + _number(c, self.name + " + c"))

    __radd__ = __add__

    def __sub__(self, c):
        return self + (-_number(c, self.name + " - c"))

    def __rsub__(self, c):
        return (-self) + c

    def __truediv__(self, k):
        return self * (1.0 / _number(k, self.name + " / k"))

    def _binding(self):
        if self.scale == 1.0 and self.offset == 0.0:
            return self.name
        return {"variable": self.name, "scale": self.scale, "offset": self.offset}

    def __repr__(self):
        return f"Variable({self.name!r}, scale={self.scale}, offset={self.offset})"


def _param(v, what):
    if isinstance(v, Variable):
        return v._binding()
    if isinstance(v, str):
        return v
    return _number(v, what)


# ---------------------------------------------------------------- the builder
class ModelBuilder:
    """Builds a case in Python (see the module's documentation)."""

    def __init__(self, name, gravity=(0.0, 0.0), description=None, base_dir=None):
        self._doc = {"name": _name(name, "name"), "gravity": _vec2(gravity, "gravity"),
                     "bodies": [], "joints": [], "forces": []}
        if description is not None:
            self._doc["description"] = str(description)
        self._base_dir = os.fspath(base_dir) if base_dir is not None else None
        self._calls = {}  # JSON path of an entry -> the call that made it
        self._names = set()
        self._variables = {}

    # ------------------------------------------------------------ bookkeeping
    @staticmethod
    def _kinds():
        return _KINDS

    def _add(self, section, entry, call, body=False):
        name = entry["name"]
        if name in self._names:
            raise _error(self, f"/{section}/{len(self._doc[section])}/name",
                         f"{call}: the name '{name}' is taken (bodies, joints and forces share one "
                         "namespace)")
        if body and name == "ground":
            raise _error(self, f"/{section}/{len(self._doc[section])}/name",
                         f"{call}: 'ground' is not a body name")
        path = f"/{section}/{len(self._doc[section])}"
        self._doc[section].append(entry)
        self._calls[path] = call
        self._names.add(name)
        return name

    @staticmethod
    def _options(entry, what, **kw):
        for k, v in kw.items():
            if v is not None:
                entry[k] = _plain(v, f"{what}: {k}")
        return entry

    # ------------------------------------------------------------ bodies
    def rigid_body(self, name, *, position=(0.0, 0.0), angle=0.0, mass=0.0, inertia=0.0, com=None,
                   velocity=None, angular_velocity=None):
        """A rigid body: position and angle of its reference point at t = 0, mass and inertia
        (about the centre of mass `com`, body frame); parameters '<name>.mass', '<name>.inertia'."""
        call = f"rigid_body({name!r})"
        e = {"name": _name(name, "rigid_body: name"), "type": "rigid",
             "position": _vec2(position, call + ": position"),
             "angle": _number(angle, call + ": angle"), "mass": _number(mass, call + ": mass"),
             "inertia": _number(inertia, call + ": inertia")}
        if com is not None:
            e["com"] = _vec2(com, call + ": com")
        if velocity is not None:
            e["velocity"] = _vec2(velocity, call + ": velocity")
        if angular_velocity is not None:
            e["angular_velocity"] = _number(angular_velocity, call + ": angular_velocity")
        return self._add("bodies", e, call, body=True)

    def flexible_body(self, name, mesh, *, E, nu, rho, thickness, origin=(0.0, 0.0), angle=0.0,
                      integration=None, velocity=None, angular_velocity=None):
        """A plane-stress body on `mesh` (lsmbs.rectangle or lsmbs.gmsh, in the body's design
        frame), placed at t = 0 by `origin` and `angle`; parameters '<name>.E', '.nu', '.rho',
        '.thickness'."""
        call = f"flexible_body({name!r})"
        if not isinstance(mesh, _Mesh):
            raise TypeError(f"{call}: mesh: expected lsmbs.rectangle(...) or lsmbs.gmsh(...), "
                            f"got {type(mesh).__name__}")
        e = {"name": _name(name, "flexible_body: name"), "type": "flexible",
             "mesh": copy.deepcopy(mesh.mesh),
             "placement": {"origin": _vec2(origin, call + ": origin"),
                           "angle": _number(angle, call + ": angle")},
             "material": {"E": _number(E, call + ": E"), "nu": _number(nu, call + ": nu"),
                          "rho": _number(rho, call + ": rho")},
             "thickness": _number(thickness, call + ": thickness")}
        if mesh.node_sets:
            e["node_sets"] = copy.deepcopy(mesh.node_sets)
        self._options(e, call, integration=integration)
        if velocity is not None:
            e["velocity"] = _vec2(velocity, call + ": velocity")
        if angular_velocity is not None:
            e["angular_velocity"] = _number(angular_velocity, call + ": angular_velocity")
        return self._add("bodies", e, call, body=True)

    # ------------------------------------------------------------ joints, drivers and forces
    # revolute, prismatic, rigid_connection, clamp, rotation_driver, translation_driver,
    # point_mass, point_force, spring_damper, torque, rotational_spring_damper, pressure: made
    # from the table of model kinds below the class (_kind_method), one method per kind.

    # ------------------------------------------------------------ simulation and output
    def simulation(self, t_end, h, **options):
        """Generalized-α options (t_end, h, rho_inf, tol_r, newton, …: the case's 'simulation')."""
        self._doc["simulation"] = {"t_end": _number(t_end, "simulation: t_end"),
                                   "h": _number(h, "simulation: h"),
                                   **_plain(options, "simulation")}
        self._calls["/simulation"] = "simulation()"

    def measure(self, name, type, **keys):
        """A measure recorded every step (history columns): type 'position', 'velocity', 'angle',
        'angular_velocity', 'distance', 'elongation', 'path_deviation', 'constraint_force',
        'kinetic_energy', 'strain_energy', 'mass', 'stress', 'frame_position', 'frame_velocity',
        'line_distance' or 'combination', with that type's keys (point=…, body=…, a=…, b=…,
        joint=…, path=…; stress: body=…, reference=…, aggregate=…, parameter=…, relaxation=…;
        frame_position, frame_velocity: point=…, frame=at('body', …); line_distance: point=…,
        a=…, b=…; combination: terms=[{'measure': 'tip.y', 'weight': 2}, …], constant=…;
        docs/case-format.md)."""
        call = f"measure({name!r})"
        e = {"name": _name(name, "measure: name"), "type": _name(type, call + ": type")}
        kind = self._kinds().get(("measures", type))
        if kind is not None:  # an unknown type: the loader names the types at build()
            known = [k["name"] for k in kind["keys"]]
            for k in keys:
                if k not in known:
                    raise TypeError(f"{call}: a '{type}' measure has no key {k!r}; its keys: "
                                    f"{', '.join(known) or 'none'}")
            for k in kind["keys"]:
                if k["required"] and k["name"] not in keys:
                    raise TypeError(f"{call}: a '{type}' measure needs {k['name']}= ({k['doc']})")
        for k, v in keys.items():
            e[k] = dict(v) if isinstance(v, _Point) else _plain(v, f"{call}: {k}")
        out = self._doc.setdefault("output", {})
        ms = out.setdefault("measures", [])
        self._calls[f"/output/measures/{len(ms)}"] = call
        ms.append(e)
        return name

    def response(self, name, measure, aggregate, *, window=None, ks=None):
        """A response: a measure column ('tip.x') aggregated ('average', 'average_eq45', 'max',
        'min', 'final', 'integral', 'rms', 'per_step', 'ks') over a window ((t0, t1), or
        {'driver': …, 'phase': …}; default the whole run)."""
        call = f"response({name!r})"
        e = {"name": _name(name, "response: name"), "measure": _name(measure, call + ": measure"),
             "aggregate": _name(aggregate, call + ": aggregate")}
        if window is not None:
            if isinstance(window, dict):
                e["window"] = _plain(window, call + ": window")
            else:
                t0, t1 = _vec2(window, call + ": window")
                e["window"] = {"t0": t0, "t1": t1}
        if ks is not None:
            e["ks"] = _number(ks, call + ": ks")
        out = self._doc.setdefault("output", {})
        rs = out.setdefault("responses", [])
        self._calls[f"/output/responses/{len(rs)}"] = call
        rs.append(e)
        return name

    def output(self, csv_stride=None, vtu_stride=None):
        """Strides of history.csv and of the VTU files (0: none)."""
        out = self._doc.setdefault("output", {})
        self._options(out, "output", csv_stride=csv_stride, vtu_stride=vtu_stride)

    # ------------------------------------------------------------ design
    def variable(self, name, initial, lower, upper):
        """A design variable; returns a Variable for feature parameters (v, 2 * v + 0.1, …)."""
        call = f"variable({name!r})"
        entry = {"name": _name(name, "variable: name"),
                 "initial": _number(initial, call + ": initial"),
                 "lower": _number(lower, call + ": lower"), "upper": _number(upper, call + ": upper")}
        vs = self._doc.get("design", {}).get("variables", [])
        if name in self._variables:
            raise _error(self, f"/design/variables/{len(vs)}/name",
                         f"{call}: duplicate design variable '{name}'")
        vs = self._doc.setdefault("design", {}).setdefault("variables", [])
        self._calls[f"/design/variables/{len(vs)}"] = call
        vs.append(entry)
        self._variables[name] = Variable(name)
        return self._variables[name]

    def features(self, body, features, *, region=None, mu_min=None, subgrid=None, band=None):
        """Level-set features on a flexible body (lsmbs.ellipse, super_ellipse, circle): by default
        the material is where every hole feature is positive (the paper's); `region` combines
        feature names with {'and': [...]}, {'or': [...]}, {'not': ...}."""
        call = f"features({body!r})"
        d = self._doc.setdefault("design", {})
        gs = d.setdefault("geometry", [])
        g = {"body": _name(body, call + ": body"), "features": [_plain(f, call) for f in features]}
        self._options(g, call, region=region, mu_min=mu_min, subgrid=subgrid, band=band)
        self._calls[f"/design/geometry/{len(gs)}"] = call
        gs.append(g)

    def bind_parameter(self, parameter, variable, scale=1.0, offset=0.0):
        """Model parameter ('spring.stiffness', 'plate.E', …) = offset + scale · variable."""
        call = f"bind_parameter({parameter!r})"
        scale, offset = _number(scale, call + ": scale"), _number(offset, call + ": offset")
        if isinstance(variable, Variable):
            variable, scale, offset = (variable.name, variable.scale * scale,
                                       variable.offset * scale + offset)
        entry = {"parameter": _name(parameter, call + ": parameter"),
                 "variable": _name(variable, call + ": variable"), "scale": scale, "offset": offset}
        ps = self._doc.setdefault("design", {}).setdefault("parameters", [])
        self._calls[f"/design/parameters/{len(ps)}"] = call
        ps.append(entry)

    # ------------------------------------------------------------ service conditions
    def condition(self, name, set=None):
        """A service condition: the model with the values of `set` changed, {JSON pointer: value}
        (docs/case-format.md, "conditions"). An array entry may be named in the pointer:
        {"/forces/payload/mass": 5.0, "/joints/drive/law": trapezoid(...), "/simulation/t_end": 3}.
        Its responses are named "<condition>.<response>"; a mass is evaluated once."""
        call = f"condition({name!r})"
        if not isinstance(name, str) or not name or "." in name:
            raise TypeError(f"{call}: expected a non-empty name without '.'")
        entry = {"name": name, "set": {}}
        for k, v in (set or {}).items():
            if not isinstance(k, str) or not k.startswith("/"):
                raise TypeError(f"{call}: set: expected JSON pointers ('/simulation/t_end'), got {k!r}")
            entry["set"][k] = _plain(v, f"{call}: set[{k!r}]")
        cs = self._doc.setdefault("conditions", [])
        if any(c["name"] == name for c in cs):
            raise _error(self, f"/conditions/{len(cs)}/name", f"{call}: duplicate condition '{name}'")
        self._calls[f"/conditions/{len(cs)}"] = call
        cs.append(entry)
        return name

    def combined(self, name, of, aggregate, *, weights=None, ks=None):
        """A response combined from others: aggregate 'sum' (weights), 'ks' (parameter ks: a
        smooth upper envelope within ln(n)/ks of the max) or 'max' (exact; as a constraint, one
        per term). `of`: a list of response names, or one name for that response of every
        condition."""
        call = f"combined({name!r})"
        e = {"name": _name(name, call + ": name"), "aggregate": _name(aggregate, call + ": aggregate"),
             "of": _name(of, call + ": of") if isinstance(of, str)
             else [_name(x, f"{call}: of") for x in of]}
        if weights is not None:
            e["weights"] = [_number(w, call + ": weights") for w in weights]
        if ks is not None:
            e["ks"] = _number(ks, call + ": ks")
        cs = self._doc.setdefault("combined", [])
        self._calls[f"/combined/{len(cs)}"] = call
        cs.append(e)
        return name

    # ------------------------------------------------------------ optimization
    def optimization(self, objective, constraints=(), **options):
        """The design problem: minimize `objective` (a response) subject to constraints, each
        (response, upper) or {'response': …, 'upper': …}; options as the case's 'optimization'
        (optimizer, sensitivity, stop, …)."""
        cons = []
        for c in constraints:
            if isinstance(c, dict):
                cons.append(_plain(c, "optimization: constraints"))
            else:
                r, up = c
                cons.append({"response": _name(r, "optimization: constraint response"),
                             "upper": _number(up, "optimization: constraint upper")})
        self._doc["optimization"] = {"objective": _name(objective, "optimization: objective"),
                                     "constraints": cons, **_plain(options, "optimization")}
        self._calls["/optimization"] = "optimization()"

    # ------------------------------------------------------------ results
    def document(self):
        """The case document (a dict in the case format; a deep copy)."""
        doc = copy.deepcopy(self._doc)
        for k in ("joints", "forces"):
            if not doc[k]:
                del doc[k]
        return doc

    def text(self):
        """The case file's text (what save() writes and build() hashes)."""
        return json.dumps(self.document(), indent=1, allow_nan=False) + "\n"

    def save(self, path):
        """Writes the case file. Relative mesh and table file names are rewritten relative to the
        file's folder, so that the saved case reads the files build() reads (the text, and so
        the hash, then differs from build()'s when the folders differ)."""
        path = pathlib.Path(path)
        base = pathlib.Path(self._base_dir if self._base_dir is not None else os.getcwd())
        doc = self.document()

        def rebase(x):
            if isinstance(x, dict):
                for k, v in x.items():
                    if k == "file" and isinstance(v, str) and not os.path.isabs(v):
                        x[k] = os.path.relpath((base / v).resolve(), path.parent.resolve())
                    else:
                        rebase(v)
            elif isinstance(x, list):
                for v in x:
                    rebase(v)

        rebase(doc)
        path.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n")

    def build(self):
        """The Case (lsmbs.Case), checked by the case-file loader; raises lsmbs.Error naming the
        call at fault."""
        if "simulation" not in self._doc:
            raise _error(self, "/simulation", "simulation(t_end=…, h=…) was not called")
        base = self._base_dir if self._base_dir is not None else os.getcwd()
        label = f"<ModelBuilder {self._doc['name']!r}>"
        try:
            return _lsmbs._load_case_text(self.text(), label, base)
        except _lsmbs.Error as e:
            raise _located(self, e) from None


# ---------------------------------------------------------------- from the table of model kinds
# The joints, forces, measures and features of the case format, with their keys, come from the
# library's table (src/lsmbs/io/model_kinds.cpp), the one the case-file loader reads them with: a
# kind added there is a method here, with the same names and the same documentation.
import inspect  # noqa: E402

_KINDS = {(k["section"], k["type"]): k for k in _lsmbs.model_kinds()}


def _convert(key, value, what):
    t = key["type"]
    if t in ("number", "non-negative number", "positive number"):
        return _number(value, what)
    if t == "integer":
        return _integer(value, what)
    if t == "boolean":
        return bool(value)
    if t == "name":
        return _name(value, what)
    if t == "[x, y]":
        return _vec2(value, what)
    if t == "[x, y, z]":
        return _vec3(value, what)
    if t == "point":
        return _point(value, what)
    if t == 'point or "ground"':
        return _point(value, what, allow_ground_word=True)
    if t == "feature parameter":
        return _param(value, what)
    if key["name"] == "control_points":  # a B-spline's [[x, y], …], each a feature parameter
        if hasattr(value, "tolist"):
            value = value.tolist()
        pts = []
        for i, p in enumerate(value):
            if not isinstance(p, (list, tuple)) or len(p) != 2:
                raise TypeError(f"{what}[{i}]: expected a control point [x, y]")
            pts.append([_param(c, f"{what}[{i}]") for c in p])
        return pts
    return _plain(value, what)  # a time law, a table, an object the kind reads itself


def _signature(kind, first):
    """first: the leading parameters (self and name for a method); then the positional keys in
    the table's order, then the keyword-only ones."""
    ps = list(first)
    for k in kind["keys"]:
        if not k["positional"]:
            continue
        default = inspect.Parameter.empty if k["required"] and k["python_default"] is None \
            else k["python_default"]
        ps.append(inspect.Parameter(k["name"], inspect.Parameter.POSITIONAL_OR_KEYWORD,
                                    default=default))
    for k in kind["keys"]:
        if not k["positional"]:
            default = inspect.Parameter.empty if k["required"] else None
            ps.append(inspect.Parameter(k["name"], inspect.Parameter.KEYWORD_ONLY, default=default))
    return inspect.Signature(ps)


def _docstring(kind):
    lines = [kind["doc"][0].upper() + kind["doc"][1:] + ".", ""]
    for k in kind["keys"]:
        need = "required" if k["required"] else "optional"
        lines.append(f"    {k['name']} ({k['type']}, {need}): {k['doc']}")
    lines += ["", "docs/case-format.md has the case format's own words for each key."]
    return "\n".join(lines)


def _kind_method(kind):
    section, type_ = kind["section"], kind["type"]
    sig = _signature(kind, [inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD),
                            inspect.Parameter("name", inspect.Parameter.POSITIONAL_OR_KEYWORD)])

    def method(self, *args, **kwargs):
        bound = sig.bind(self, *args, **kwargs)
        bound.apply_defaults()
        name = bound.arguments["name"]
        call = f"{type_}({name!r})"
        e = {"name": _name(name, f"{type_}: name"), "type": type_}
        for k in kind["keys"]:
            v = bound.arguments.get(k["name"])
            if v is not None:
                e[k["name"]] = _convert(k, v, f"{call}: {k['name']}")
        return self._add(section, e, call)

    method.__name__ = method.__qualname__ = type_
    method.__signature__ = sig
    method.__doc__ = _docstring(kind)
    return method


def _feature_function(kind):
    type_ = kind["type"]
    sig = _signature(kind, [inspect.Parameter("name", inspect.Parameter.POSITIONAL_OR_KEYWORD)])

    def feature(*args, **kwargs):
        bound = sig.bind(*args, **kwargs)
        bound.apply_defaults()
        name = bound.arguments["name"]
        f = {"name": _name(name, f"{type_}: name"), "type": type_}
        if not bound.arguments.get("non_design"):  # a non-design feature is solid: no "hole"
            f["hole"] = bool(bound.arguments.get("hole"))
        for k in kind["keys"]:
            v = bound.arguments.get(k["name"])
            if v is not None and k["name"] not in f and k["name"] != "hole":
                f[k["name"]] = _convert(k, v, f"{type_} '{name}': {k['name']}")
        return f

    feature.__name__ = feature.__qualname__ = type_
    feature.__signature__ = sig
    feature.__doc__ = _docstring(kind) + "\n\nEach parameter: a number, a Variable or a variable name."
    return feature


for (_section, _type), _kind in _KINDS.items():
    if _section in ("joints", "forces"):
        setattr(ModelBuilder, _type, _kind_method(_kind))
    elif _section == "features":
        globals()[_type] = _feature_function(_kind)


# ---------------------------------------------------------------- spatial cases
_SPATIAL_KINDS = {(k["section"], k["type"]): k for k in _lsmbs.spatial_model_kinds()}


class SpatialModelBuilder(ModelBuilder):
    """Builds a spatial case ("dimension": 3; docs/case-format.md, "Spatial cases"): rigid bodies
    in space, joints between two bodies (or a body and "ground") given by their point and axes
    at t = 0, forces and measures of the spatial kinds. Simulation, responses, design variables
    bound to model parameters, optimization and conditions are the planar builder's.

        m = lsmbs.SpatialModelBuilder("top", gravity=(0, 0, -9.81))
        m.rigid_body("disc", position=(0, 0, 0.1), mass=1, inertia=(0.004, 0.004, 0.006),
                     angular_velocity=(0, 0, 40))
        m.spherical("tip", "ground", "disc", at=(0, 0, 0))
    """

    def __init__(self, name, gravity=(0.0, 0.0, 0.0), description=None, base_dir=None):
        super().__init__(name, (0.0, 0.0), description, base_dir)
        self._doc["dimension"] = 3
        self._doc["gravity"] = _vec3(gravity, "gravity")

    @staticmethod
    def _kinds():
        return _SPATIAL_KINDS

    def rigid_body(self, name, *, position=(0.0, 0.0, 0.0), orientation=None, mass=0.0,
                   inertia=(0.0, 0.0, 0.0), velocity=None, angular_velocity=None):
        """A spatial rigid body: its centre of mass at t = 0, its principal axes (orientation: a
        3 × 3 rotation matrix whose columns are the axes, or {'axis': (x, y, z), 'angle': rad}),
        mass and principal moments (I1, I2, I3); velocity of the centre of mass and angular
        velocity (ground components) at t = 0 are kept when given. Parameters '<name>.mass',
        '<name>.I1', '.I2', '.I3'."""
        call = f"rigid_body({name!r})"
        e = {"name": _name(name, "rigid_body: name"), "type": "rigid",
             "position": _vec3(position, call + ": position"),
             "mass": _number(mass, call + ": mass"),
             "inertia": _vec3(inertia, call + ": inertia")}
        if orientation is not None:
            if isinstance(orientation, collections.abc.Mapping):
                e["orientation"] = {"axis": _vec3(orientation.get("axis"), call + ": orientation"),
                                    "angle": _number(orientation.get("angle"),
                                                     call + ": orientation angle")}
            else:
                if hasattr(orientation, "tolist"):
                    orientation = orientation.tolist()
                e["orientation"] = [_vec3(r, f"{call}: orientation[{i}]")
                                    for i, r in enumerate(orientation)]
        if velocity is not None:
            e["velocity"] = _vec3(velocity, call + ": velocity")
        if angular_velocity is not None:
            e["angular_velocity"] = _vec3(angular_velocity, call + ": angular_velocity")
        return self._add("bodies", e, call, body=True)

    def solid_body(self, name, *, size, elements, E, nu, rho, origin=(0.0, 0.0, 0.0),
                   formulation="enhanced"):
        """A 3D solid flexible body: the box [origin, origin + size] (ground coordinates at t = 0)
        in elements = (nx, ny, nz) hexahedra, with the node sets 'xmin' … 'zmax' of its faces;
        St Venant–Kirchhoff with E, nu, rho (parameters '<name>.E', '.nu', '.rho'); formulation
        'enhanced' (default: no locking) or 'full'. Tie it with solid_connection, measure it with
        node_set_position."""
        call = f"solid_body({name!r})"
        try:
            n = [operator.index(v) if not isinstance(v, float) else v for v in elements]
        except TypeError:
            n = None
        if not n or len(n) != 3 or not all(v >= 1 and v == int(v) for v in n):
            raise ValueError(f"{call}: elements: expected three positive integers (nx, ny, nz)")
        n = [int(v) for v in n]
        e = {"name": _name(name, "solid_body: name"), "type": "solid",
             "mesh": {"type": "box", "origin": _vec3(origin, call + ": origin"),
                      "size": _vec3(size, call + ": size"), "elements": n},
             "material": {"E": _number(E, call + ": E"), "nu": _number(nu, call + ": nu"),
                          "rho": _number(rho, call + ": rho")},
             "formulation": formulation}
        return self._add("bodies", e, call, body=True)

    def flexible_body(self, *args, **kwargs):
        raise NotImplementedError("plane-stress flexible bodies are planar; a flexible component "
                                  "of a spatial mechanism is a solid_body")

    def features(self, body, features, *, region=None, mu_min=None, subgrid=None, band=None):
        """3D level-set features on a solid body (lsmbs.sphere, cylinder, super_ellipsoid,
        pocket, through_hole; docs/case-format.md, "Designs of solid bodies"): by default the
        material is where every hole feature is positive; `region` combines feature names with
        {'and': [...]}, {'or': [...]}, {'not': ...}."""
        super().features(body, features, region=region, mu_min=mu_min, subgrid=subgrid, band=band)


# ---------------------------------------------------------------- 3D features (solid bodies)
def _feature3(name, type_, params, hole, non_design, **extra):
    what = f"{type_} {name!r}"
    f = {"name": _name(name, f"{type_}: name"), "type": type_}
    if non_design:
        f["non_design"] = True
    else:
        f["hole"] = bool(hole)
    for k, v in extra.items():
        if v is not None:
            f[k] = v
    for k, v in params.items():
        if v is not None:
            f[k] = _param(v, f"{what}: {k}")
    return f


def sphere(name, cx, cy, cz, r, *, hole=True, non_design=False):
    """A spherical hole (or with hole=False a solid ball) of radius r about (cx, cy, cz) [m].
    Each parameter: a number, a Variable or a variable name."""
    return _feature3(name, "sphere", dict(cx=cx, cy=cy, cz=cz, r=r), hole, non_design)


def cylinder(name, cx, cy, cz, r, *, length=None, axis=(0.0, 0.0, 1.0), hole=True,
             non_design=False):
    """A round bore of radius r along `axis` through (cx, cy, cz), through the whole part, or
    capped at ±length/2 from the centre."""
    return _feature3(name, "cylinder", dict(cx=cx, cy=cy, cz=cz, r=r, length=length), hole,
                     non_design, axis=_vec3(axis, f"cylinder {name!r}: axis"))


def super_ellipsoid(name, cx, cy, cz, a, b, c, xi, *, orientation=None, hole=True,
                    non_design=False):
    """|u/a|^xi + |v/b|^xi + |w/c|^xi <= 1 (xi >= 2: a rounded box) in the frame turned by
    `orientation` ({'axis': (x, y, z), 'angle': rad} or a 3 x 3 matrix by rows)."""
    if orientation is not None and not isinstance(orientation, collections.abc.Mapping):
        if hasattr(orientation, "tolist"):
            orientation = orientation.tolist()
        orientation = [_vec3(r, f"super_ellipsoid {name!r}: orientation") for r in orientation]
    return _feature3(name, "super_ellipsoid", dict(cx=cx, cy=cy, cz=cz, a=a, b=b, c=c, xi=xi),
                     hole, non_design, orientation=orientation)


def _profile(name, type_, profile):
    """The planar feature `profile` (lsmbs.circle, ellipse or super_ellipse) as a pocket's or
    through-hole's profile: its type and parameters."""
    if not isinstance(profile, collections.abc.Mapping) or profile.get("type") not in (
            "circle", "ellipse", "super_ellipse"):
        raise ValueError(f"{type_} {name!r}: profile: expected a planar circle, ellipse or "
                         f"super_ellipse (lsmbs.circle(...), ...)")
    params = {k: v for k, v in profile.items() if k not in ("name", "type", "hole", "non_design")}
    return profile["type"], params


def _face(name, type_, face):
    if isinstance(face, str):
        return face
    if isinstance(face, collections.abc.Mapping):
        return {k: _vec3(face.get(k), f"{type_} {name!r}: face {k}")
                for k in ("origin", "normal", "u_axis")}
    raise ValueError(f"{type_} {name!r}: face: expected 'xmin' ... 'zmax' or "
                     f"{{'origin', 'normal', 'u_axis'}}")


def pocket(name, face, profile, depth, *, hole=True, non_design=False):
    """A planar profile (lsmbs.circle, ellipse or super_ellipse, its centre in the face's (u, v))
    machined from `face` ('xmin' ... 'zmax' of the body's box, or {'origin', 'normal' (into the
    part), 'u_axis'}) to `depth` [m]."""
    ptype, params = _profile(name, "pocket", profile)
    params["depth"] = depth
    return _feature3(name, "pocket", params, hole, non_design, face=_face(name, "pocket", face),
                     profile=ptype)


def through_hole(name, face, profile, *, hole=True, non_design=False):
    """A planar profile through the whole part, normal to `face` (as for pocket)."""
    ptype, params = _profile(name, "through_hole", profile)
    return _feature3(name, "through_hole", params, hole, non_design,
                     face=_face(name, "through_hole", face), profile=ptype)


# the spatial kinds replace the planar ones of the same name on SpatialModelBuilder; planar
# kinds with no spatial counterpart are not available there
def _planar_only(type_):
    def method(self, *args, **kwargs):
        raise NotImplementedError(f"{type_}: a planar kind; spatial cases have "
                                  f"{', '.join(sorted(t for s, t in _SPATIAL_KINDS if s != 'measures'))}")

    method.__name__ = method.__qualname__ = type_
    return method


for (_section, _type), _kind in _KINDS.items():
    if _section in ("joints", "forces") and (_section, _type) not in _SPATIAL_KINDS:
        setattr(SpatialModelBuilder, _type, _planar_only(_type))
for (_section, _type), _kind in _SPATIAL_KINDS.items():
    if _section in ("joints", "forces"):
        setattr(SpatialModelBuilder, _type, _kind_method(_kind))



def _error(builder, path, message):
    e = _lsmbs.Error(f"<ModelBuilder {builder._doc['name']!r}>: {path}: {message}")
    e.file, e.json_path, e.reason = f"<ModelBuilder {builder._doc['name']!r}>", path, message
    return e


def _located(builder, e):
    """The loader's error with the builder call that made the entry in front."""
    path = getattr(e, "json_path", "") or ""
    reason = getattr(e, "reason", str(e))
    best = ""
    for p in builder._calls:
        if (path == p or path.startswith(p + "/")) and len(p) > len(best):
            best = p
    if not best:
        return _error(builder, path, reason)
    rest = path[len(best):].lstrip("/")
    return _error(builder, path, f"{builder._calls[best]}: {rest + ': ' if rest else ''}{reason}")
