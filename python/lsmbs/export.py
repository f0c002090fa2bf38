"""Export of a designed body to CAD and meshing formats, from the shape file that `lsmbs geometry`
and `lsmbs optimize` write beside each design picture (``<body>_shape.json``: the mesh's outline,
the level-set features with their values at the design, the Boolean region, the node sets, the
thickness; src/lsmbs/runs/shape.hpp).

    from lsmbs import export
    files = export.export("out/final_design/plate_shape.json", "out/cad")
    # {'dxf': ..., 'svg': ..., 'step': ..., 'msh': ...}

    python3 scripts/export_design.py out/final_design/plate_shape.json -o out/cad

Formats (CAD files in millimetres, the mesh in metres like lsmbs):
  dxf   ezdxf: layer OUTLINE the body's outline (the fixed mesh's boundary loops), layer FEATURES
        every feature as an exact entity where DXF has one (CIRCLE, ELLIPSE, the B-spline
        feature's own SPLINE: its control points, degree 3, uniform knots) and a closed SPLINE
        through 256 boundary points for a super-ellipse, layer COMPONENT the boundary of the
        Boolean result (LINE, ARC and ELLIPSE arcs where a feature's boundary is exact, else a
        SPLINE through points of the curve);
  svg   the same layers as groups (<polygon>, <circle>, <ellipse>, paths; a B-spline feature as
        its exact cubic Bézier segments), written with xml.etree;
  step  Gmsh's OpenCASCADE kernel: the component's face (the outline less the holes, with the
        region's Boolean operations as OCC Booleans) extruded by the thickness;
  msh   a body-fitted Gmsh mesh (Gmsh 4.1 ASCII, quadrilaterals where the recombination finds
        them, triangles elsewhere) of element size `size` (default: the fixed mesh's), with a
        physical curve for each node set of the body whose nodes lie along a boundary curve of
        the design; lsmbs reads it as an ordinary flexible body (body_fitted_case).
A region combined with KS smoothing (ks > 0) is exported with the exact Boolean (the smoothing
moves the boundary by at most ln(n)/ks, stated in the returned `notes`).
"""
import json
import math
import os
import xml.etree.ElementTree as ET

__all__ = ["load_shape", "feature_points", "bezier_segments", "bspline_area", "write_dxf", "write_svg", "write_step", "write_msh",
           "write_msh_solid", "write_section_png", "component_area", "component_volume", "export", "body_fitted_case"]

MM = 1000.0  # CAD files: millimetres


def load_shape(shape):
    """The shape as a dict (a path to a ``*_shape.json`` file, or the dict itself)."""
    if isinstance(shape, dict):
        return shape
    with open(os.fspath(shape)) as f:
        return json.load(f)


def _frame(p):
    a = p.get("angle", 0.0)
    return p["cx"], p["cy"], math.cos(a), math.sin(a)


def bezier_segments(feature):
    """A closed uniform cubic B-spline feature as its cubic Bézier segments, exactly: per span k
    (control points P_k … P_k+3) B0 = (P0 + 4 P1 + P2)/6, B1 = (2 P1 + P2)/3, B2 = (P1 + 2 P2)/3,
    B3 = (P1 + 4 P2 + P3)/6 (B3 of one span is B0 of the next)."""
    P = feature["control_points"]
    n = len(P)
    segs = []
    for k in range(n):
        p0, p1, p2, p3 = (P[(k + i) % n] for i in range(4))
        segs.append([tuple((a + 4 * b + c) / 6 for a, b, c in zip(p0, p1, p2)),
                     tuple((2 * b + c) / 3 for b, c in zip(p1, p2)),
                     tuple((b + 2 * c) / 3 for b, c in zip(p1, p2)),
                     tuple((b + 4 * c + d) / 6 for b, c, d in zip(p1, p2, p3))])
    return segs


def bspline_area(control_points):
    """The area inside the closed uniform cubic B-spline of the control points [[x, y], …],
    exactly: ½∮(x dy − y dx) over its Bézier segments (a polynomial of degree 5 in each:
    3-point Gauss–Legendre is exact)."""
    segs = bezier_segments({"control_points": control_points})
    g = [(-math.sqrt(0.6), 5 / 9), (0.0, 8 / 9), (math.sqrt(0.6), 5 / 9)]
    area = 0.0
    for B in segs:
        for x, w in g:
            u = 0.5 * (x + 1)
            b = ((1 - u) ** 3, 3 * u * (1 - u) ** 2, 3 * u * u * (1 - u), u ** 3)
            db = (-3 * (1 - u) ** 2, 3 * (1 - u) ** 2 - 6 * u * (1 - u), 6 * u * (1 - u) - 3 * u * u,
                  3 * u * u)
            c = [sum(bi * q[i] for bi, q in zip(b, B)) for i in (0, 1)]
            d = [sum(bi * q[i] for bi, q in zip(db, B)) for i in (0, 1)]
            area += 0.25 * w * (c[0] * d[1] - c[1] * d[0])
    return abs(area)


def feature_points(feature, n=256):
    """n points of the feature's exact boundary (eqs. 41, 43; a B-spline's curve), in metres:
    counter-clockwise, a B-spline's in the order of its control points."""
    p, t = feature["params"], feature["type"]
    if t == "bspline":
        segs = bezier_segments(feature)
        out = []
        for k in range(n):
            s = len(segs) * k / n
            b, u = segs[int(s)], s - int(s)
            w = ((1 - u) ** 3, 3 * u * (1 - u) ** 2, 3 * u * u * (1 - u), u ** 3)
            out.append(tuple(sum(wi * q[i] for wi, q in zip(w, b)) for i in range(2)))
        return out
    cx, cy, c, s = _frame(p)
    out = []
    for k in range(n):
        th = 2 * math.pi * k / n
        if t == "circle":
            u, v = p["r"] * math.cos(th), p["r"] * math.sin(th)
        elif t == "ellipse":
            u, v = p["a"] * p["d"] * math.cos(th), p["b"] * p["d"] * math.sin(th)
        else:  # |u/a|^xi + |v/b|^eta = 1
            ct, st = math.cos(th), math.sin(th)
            u = p["a"] * math.copysign(abs(ct) ** (2 / p["xi"]), ct)
            v = p["b"] * math.copysign(abs(st) ** (2 / p["eta"]), st)
        out.append((cx + c * u - s * v, cy + s * u + c * v))
    return out


def _phi(feature, x, y):
    """The feature's level-set function (positive outside its shape), for matching curves."""
    p, t = feature["params"], feature["type"]
    cx, cy, c, s = _frame(p)
    u, v = c * (x - cx) + s * (y - cy), -s * (x - cx) + c * (y - cy)
    if t == "circle":
        return math.hypot(u, v) - p["r"]
    if t == "ellipse":
        return (math.hypot(u / p["a"], v / p["b"]) - p["d"]) * min(p["a"], p["b"])
    return (abs(u / p["a"]) ** p["xi"] + abs(v / p["b"]) ** p["eta"] - 1) * min(p["a"], p["b"])


def _semi_axes(feature):
    """Centre, semi-axes (major, minor) and the major axis's direction of a circle or ellipse."""
    p = feature["params"]
    cx, cy, c, s = _frame(p)
    if feature["type"] == "circle":
        return (cx, cy), p["r"], p["r"], (1.0, 0.0)
    a, b = p["a"] * p["d"], p["b"] * p["d"]
    if a >= b:
        return (cx, cy), a, b, (c, s)
    return (cx, cy), b, a, (-s, c)


# ----------------------------------------------------------------------------- OpenCASCADE
def _occ_feature(gmsh, feature):
    occ = gmsh.model.occ
    t = feature["type"]
    if t in ("circle", "ellipse"):
        (cx, cy), ra, rb, (dx, dy) = _semi_axes(feature)
        tag = occ.addDisk(cx, cy, 0, ra, rb)
        ang = math.atan2(dy, dx)
        if ang != 0:
            occ.rotate([(2, tag)], cx, cy, 0, 0, 0, 1, ang)
        return tag
    if t == "bspline":  # exact: its Bézier segments, sharing their end points
        segs = bezier_segments(feature)
        ends = [occ.addPoint(b[0][0], b[0][1], 0) for b in segs]
        curves = []
        for k, b in enumerate(segs):
            inner = [occ.addPoint(x, y, 0) for x, y in b[1:3]]
            curves.append(occ.addBezier([ends[k]] + inner + [ends[(k + 1) % len(segs)]]))
        return occ.addPlaneSurface([occ.addCurveLoop(curves)])
    pts = [occ.addPoint(x, y, 0) for x, y in feature_points(feature, 128)]
    curve = occ.addSpline(pts + [pts[0]])  # first point repeated: a periodic spline
    return occ.addPlaneSurface([occ.addCurveLoop([curve])])


def _corners(loop):
    """The loop without the points where it runs straight on (a mesh's boundary nodes along a
    straight edge): one line per straight edge."""
    n, out = len(loop), []
    for k in range(n):
        (ax, ay), (bx, by), (cx, cy) = loop[k - 1], loop[k], loop[(k + 1) % n]
        cross = (bx - ax) * (cy - by) - (by - ay) * (cx - bx)
        if abs(cross) > 1e-12 * math.hypot(bx - ax, by - ay) * math.hypot(cx - bx, cy - by):
            out.append(loop[k])
    return out or loop


def _occ_outline(gmsh, shape):
    """The body's face: its outer loop less its inner loops (OCC cut: a face made of several
    wires at once came out with the holes' areas added on the connecting rod's mesh)."""
    occ = gmsh.model.occ
    faces = []
    for loop in (_corners(l) for l in shape["outline"]):
        pts = [occ.addPoint(x, y, 0) for x, y in loop]
        lines = [occ.addLine(pts[k], pts[(k + 1) % len(pts)]) for k in range(len(pts))]
        area = 0.5 * sum(loop[k][0] * loop[(k + 1) % len(loop)][1] -
                         loop[(k + 1) % len(loop)][0] * loop[k][1] for k in range(len(loop)))
        faces.append((area, occ.addPlaneSurface([occ.addCurveLoop(lines)])))
    faces.sort(key=lambda af: -af[0])  # the outer loop (positive area) first
    outer, holes = faces[0][1], [(2, t) for _, t in faces[1:]]
    if not holes:
        return outer
    (dim, tag), = occ.cut([(2, outer)], holes)[0]
    return tag


def _occ_region(gmsh, shape, node, domain, notes, dim=2, build=None):
    """OCC entities (faces, or volumes with dim = 3) of the material of a region node, within a
    copy of the domain; build(gmsh, feature) makes a feature's shape (default: a planar one)."""
    occ = gmsh.model.occ
    feats = shape["features"]
    build = build or _occ_feature

    def copy():
        return occ.copy([(dim, domain)])

    def region(k):
        return _occ_region(gmsh, shape, k, domain, notes, dim, build)

    op = node["op"]
    if op == "feature":
        f = feats[node["feature"]]
        tool = [(dim, build(gmsh, f))]
        if f["hole"]:
            return occ.cut(copy(), tool)[0]
        return occ.intersect(copy(), tool)[0]
    if op == "not":
        inner = region(node["children"][0])
        return occ.cut(copy(), inner)[0] if inner else copy()
    if node.get("ks", 0) > 0:
        notes.append("a %s combined by KS (ks = %g 1/m) is exported with the exact Boolean: the "
                     "smoothing moves the boundary by at most ln(%d)/ks = %.3g m" % (
                         op, node["ks"], len(node["children"]),
                         math.log(len(node["children"])) / node["ks"]))
    kids = node["children"]
    if op == "and" and all(k["op"] == "feature" and feats[k["feature"]]["hole"] for k in kids):
        tools = [(dim, build(gmsh, feats[k["feature"]])) for k in kids]  # the paper's eq. 4
        return occ.cut(copy(), tools)[0] if tools else copy()
    parts = [region(k) for k in kids]
    acc = parts[0]
    for p in parts[1:]:
        if op == "and":
            acc = occ.intersect(acc, p)[0] if acc and p else []
        else:
            # the union as non-overlapping faces: OpenCASCADE's fuse of two coplanar faces that
            # share an edge (a non-design ring's bore, cut from copies of one outline) returned
            # both faces whole, overlapping (the rod with rings had 1.48 times its area)
            acc = occ.fragment(acc, p)[0] if acc and p else (acc or p)
    return acc


def _component(gmsh, shape, notes):
    """Builds the component's faces in the current Gmsh model; returns their tags."""
    domain = _occ_outline(gmsh, shape)
    faces = _occ_region(gmsh, shape, shape["region"], domain, notes)
    gmsh.model.occ.remove([(2, domain)], recursive=True)
    gmsh.model.occ.synchronize()
    return [t for d, t in faces if d == 2]


class _quiet_stdout:
    """File descriptor 1 to /dev/null (output of C++ code that Gmsh's options do not silence)."""

    def __enter__(self):
        import sys
        sys.stdout.flush()
        self.saved = os.dup(1)
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.close(null)

    def __exit__(self, *exc):
        os.dup2(self.saved, 1)
        os.close(self.saved)


class _Gmsh:
    """A Gmsh session (gmsh keeps one global state): quiet, one model."""

    def __enter__(self):
        import gmsh
        self.gmsh = gmsh
        gmsh.initialize(readConfigFiles=False)
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("lsmbs_design")
        return gmsh

    def __exit__(self, *exc):
        self.gmsh.finalize()


def component_area(shape):
    """Area of the exported component [m²] (OpenCASCADE's exact area of the Boolean result)."""
    shape = load_shape(shape)
    with _Gmsh() as gmsh:
        faces = _component(gmsh, shape, [])
        return sum(gmsh.model.occ.getMass(2, f) for f in faces)


def _curves(gmsh, faces, samples=64):
    """The boundary curves of the faces: (kind, points) with points sampled along each."""
    out = []
    seen = set()
    for _, c in gmsh.model.getBoundary([(2, f) for f in faces], combined=True, oriented=False):
        c = abs(c)
        if c in seen:
            continue
        seen.add(c)
        lo, hi = gmsh.model.getParametrizationBounds(1, c)
        ts = [lo[0] + (hi[0] - lo[0]) * k / samples for k in range(samples + 1)]
        xyz = gmsh.model.getValue(1, c, ts)
        pts = [(xyz[3 * k], xyz[3 * k + 1]) for k in range(len(ts))]
        out.append((gmsh.model.getType(1, c), pts))
    return out


def _match(shape, pts, tol):
    """The circle or ellipse feature whose exact boundary holds every point, or None."""
    for f in shape["features"]:
        if f["type"] in ("circle", "ellipse") and all(abs(_phi(f, x, y)) <= tol for x, y in pts):
            return f
    return None


def _arc_params(f, pts):
    """Start, end (counter-clockwise, radians of the ellipse's parameter) of an arc through pts."""
    (cx, cy), ra, rb, (dx, dy) = _semi_axes(f)

    def param(x, y):
        u, v = dx * (x - cx) + dy * (y - cy), -dy * (x - cx) + dx * (y - cy)
        return math.atan2(v / rb, u / ra)

    t0, t1, tm = param(*pts[0]), param(*pts[-1]), param(*pts[len(pts) // 2])

    def ccw(a, b):  # the counter-clockwise angle from a to b, in [0, 2π)
        return (b - a) % (2 * math.pi)

    if ccw(t0, tm) <= ccw(t0, t1):
        return t0, t1
    return t1, t0


def _component_curves(shape, notes):
    with _Gmsh() as gmsh:
        faces = _component(gmsh, shape, notes)
        return _curves(gmsh, faces)


# ----------------------------------------------------------------------------- DXF
def write_dxf(shape, path, notes=None):
    """The DXF file (millimetres, $INSUNITS 4); returns the path."""
    import ezdxf
    shape = load_shape(shape)
    notes = [] if notes is None else notes
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    for name, color in (("OUTLINE", 8), ("FEATURES", 1), ("COMPONENT", 7)):
        doc.layers.add(name, color=color)
    msp = doc.modelspace()
    for loop in shape["outline"]:
        msp.add_lwpolyline([(x * MM, y * MM) for x, y in loop], close=True,
                           dxfattribs={"layer": "OUTLINE"})
    for f in shape["features"]:
        _dxf_feature(msp, f, "FEATURES")
    tol = 1e-6 * max(1e-3, shape.get("element_size", 1e-3))
    for kind, pts in _component_curves(shape, notes):
        _dxf_curve(msp, shape, kind, pts, tol)
    doc.saveas(os.fspath(path))
    return os.fspath(path)


def _dxf_feature(msp, f, layer):
    at = {"layer": layer}
    if f["type"] == "circle":
        p = f["params"]
        msp.add_circle((p["cx"] * MM, p["cy"] * MM), p["r"] * MM, dxfattribs=at)
    elif f["type"] == "ellipse":
        (cx, cy), ra, rb, (dx, dy) = _semi_axes(f)
        msp.add_ellipse((cx * MM, cy * MM), (ra * dx * MM, ra * dy * MM), rb / ra,
                        dxfattribs=at)
    elif f["type"] == "bspline":
        # the periodic curve as an open B-spline: the control points with the first three
        # repeated, uniform knots 0 … n + 6 (its domain [3, n + 3] is the closed curve)
        P = [(x * MM, y * MM) for x, y in f["control_points"]]
        msp.add_open_spline(P + P[:3], degree=3, knots=list(range(len(P) + 7)), dxfattribs=at)
    else:
        pts = [(x * MM, y * MM) for x, y in feature_points(f)]
        msp.add_spline_control_frame(pts + [pts[0]], dxfattribs=at)


def _dxf_curve(msp, shape, kind, pts, tol):
    at = {"layer": "COMPONENT"}
    closed = math.dist(pts[0], pts[-1]) <= tol * 10
    if kind == "Line":
        msp.add_line((pts[0][0] * MM, pts[0][1] * MM), (pts[-1][0] * MM, pts[-1][1] * MM),
                     dxfattribs=at)
        return
    f = _match(shape, pts, tol * 10) if kind in ("Circle", "Ellipse") else None
    if f is not None and closed:
        _dxf_feature(msp, f, "COMPONENT")
        return
    if f is not None:
        t0, t1 = _arc_params(f, pts)
        (cx, cy), ra, rb, (dx, dy) = _semi_axes(f)
        if f["type"] == "circle":
            msp.add_arc((cx * MM, cy * MM), ra * MM, math.degrees(t0), math.degrees(t1),
                        dxfattribs=at)
        else:
            msp.add_ellipse((cx * MM, cy * MM), (ra * dx * MM, ra * dy * MM), rb / ra,
                            start_param=t0, end_param=t1, dxfattribs=at)
        return
    msp.add_spline_control_frame([(x * MM, y * MM) for x, y in pts], dxfattribs=at)


# ----------------------------------------------------------------------------- SVG
def write_svg(shape, path, notes=None):
    """The SVG file (user units = millimetres, y up as in the body's frame); returns the path."""
    shape = load_shape(shape)
    notes = [] if notes is None else notes
    xs = [x for loop in shape["outline"] for x, _ in loop]
    ys = [y for loop in shape["outline"] for _, y in loop]
    pad = 0.02 * max(max(xs) - min(xs), max(ys) - min(ys))
    x0, y0 = (min(xs) - pad) * MM, (min(ys) - pad) * MM
    w, h = (max(xs) - min(xs) + 2 * pad) * MM, (max(ys) - min(ys) + 2 * pad) * MM
    ET.register_namespace("", "http://www.w3.org/2000/svg")
    svg = ET.Element("{http://www.w3.org/2000/svg}svg", {
        "width": "%gmm" % w, "height": "%gmm" % h, "viewBox": "%g %g %g %g" % (x0, -y0 - h, w, h)})
    ET.SubElement(svg, "title").text = "%s (lsmbs design export, mm)" % shape.get("body", "")
    flip = ET.SubElement(svg, "g", {"transform": "scale(1,-1)", "fill": "none",
                                    "stroke-width": "%g" % (0.002 * max(w, h))})
    outline = ET.SubElement(flip, "g", {"id": "OUTLINE", "stroke": "#888888"})
    for loop in shape["outline"]:
        ET.SubElement(outline, "polygon",
                      {"points": " ".join("%.6g,%.6g" % (x * MM, y * MM) for x, y in loop)})
    feats = ET.SubElement(flip, "g", {"id": "FEATURES", "stroke": "#cc0000"})
    for f in shape["features"]:
        _svg_feature(feats, f)
    comp = ET.SubElement(flip, "g", {"id": "COMPONENT", "stroke": "#000000"})
    tol = 1e-6 * max(1e-3, shape.get("element_size", 1e-3))
    for kind, pts in _component_curves(shape, notes):
        _svg_curve(comp, shape, kind, pts, tol)
    ET.ElementTree(svg).write(os.fspath(path), xml_declaration=True, encoding="utf-8")
    return os.fspath(path)


def _svg_feature(g, f, attrs=None):
    attrs = dict(attrs or {}, id=f["name"])
    if f["type"] == "circle":
        p = f["params"]
        ET.SubElement(g, "circle", dict(attrs, cx="%.9g" % (p["cx"] * MM),
                                         cy="%.9g" % (p["cy"] * MM), r="%.9g" % (p["r"] * MM)))
    elif f["type"] == "ellipse":
        (cx, cy), ra, rb, (dx, dy) = _semi_axes(f)
        ET.SubElement(g, "ellipse", dict(
            attrs, cx="%.9g" % (cx * MM), cy="%.9g" % (cy * MM), rx="%.9g" % (ra * MM),
            ry="%.9g" % (rb * MM), transform="rotate(%.9g %.9g %.9g)" % (
                math.degrees(math.atan2(dy, dx)), cx * MM, cy * MM)))
    elif f["type"] == "bspline":
        segs = bezier_segments(f)
        d = "M %.9g %.9g" % (segs[0][0][0] * MM, segs[0][0][1] * MM) + "".join(
            " C " + " ".join("%.9g %.9g" % (x * MM, y * MM) for x, y in b[1:]) for b in segs)
        ET.SubElement(g, "path", dict(attrs, d=d + " Z"))
    else:
        pts = feature_points(f)
        d = "M " + " L ".join("%.6g %.6g" % (x * MM, y * MM) for x, y in pts) + " Z"
        ET.SubElement(g, "path", dict(attrs, d=d))


def _svg_curve(g, shape, kind, pts, tol):
    closed = math.dist(pts[0], pts[-1]) <= tol * 10
    f = _match(shape, pts, tol * 10) if kind in ("Circle", "Ellipse") else None
    if f is not None and closed:
        _svg_feature(g, f, {"class": "component"})
        return
    d = "M %.6g %.6g" % (pts[0][0] * MM, pts[0][1] * MM)
    if kind == "Line":
        d += " L %.6g %.6g" % (pts[-1][0] * MM, pts[-1][1] * MM)
    elif f is not None:  # an exact elliptic arc from the first point to the last
        (cx, cy), ra, rb, (dx, dy) = _semi_axes(f)
        t0, t1 = _arc_params(f, pts)
        forward = math.dist(pts[0], _ellipse_point(f, t0)) <= math.dist(pts[0], _ellipse_point(f, t1))
        span = (t1 - t0) % (2 * math.pi)
        d += " A %.9g %.9g %.9g %d %d %.6g %.6g" % (
            ra * MM, rb * MM, math.degrees(math.atan2(dy, dx)), 1 if span > math.pi else 0,
            1 if forward else 0, pts[-1][0] * MM, pts[-1][1] * MM)
    else:
        d += "".join(" L %.6g %.6g" % (x * MM, y * MM) for x, y in pts[1:])
    ET.SubElement(g, "path", {"d": d})


def _ellipse_point(f, t):
    (cx, cy), ra, rb, (dx, dy) = _semi_axes(f)
    u, v = ra * math.cos(t), rb * math.sin(t)
    return (cx + dx * u - dy * v, cy + dy * u + dx * v)


# ----------------------------------------------------------------------------- STEP, MSH
def write_step(shape, path, notes=None):
    """The STEP solid (millimetres): a planar design's face extruded by the thickness, or a solid
    design's volume."""
    # built in millimetres (OpenCASCADE's dilate would turn circles and ellipses into splines)
    shape = load_shape(shape)
    if shape.get("kind") == "solid":
        shape = _scaled3(shape, MM)
        with _Gmsh() as gmsh:
            _solid_component(gmsh, shape, [] if notes is None else notes)
            with _quiet_stdout():
                gmsh.write(os.fspath(path))
        return os.fspath(path)
    shape = _scaled(shape, MM)
    with _Gmsh() as gmsh:
        faces = _component(gmsh, shape, [] if notes is None else notes)
        occ = gmsh.model.occ
        occ.extrude([(2, f) for f in faces], 0, 0, shape["thickness"])
        occ.synchronize()
        with _quiet_stdout():  # OpenCASCADE's STEP writer prints its statistics
            gmsh.write(os.fspath(path))
    return os.fspath(path)


# ----------------------------------------------------------------------------- solid designs
# A solid body's shape ("kind": "solid", src/lsmbs/runs/shape.hpp): its box domain less (or with)
# the 3D features, as OpenCASCADE volumes: spheres and cylinders exactly, a pocket or a
# through-hole as its planar profile (exact circles and ellipses, a spline through 128 points of
# a super-ellipse) extruded along the face's w and placed by the feature's frame. A pocket's
# prism runs from outside the part (w < 0, where the level set has no bound either) to its
# depth. Super-ellipsoids have no exact CAD solid and are refused.
_LENGTHS3 = {"cx", "cy", "cz", "a", "b", "c", "r", "length", "depth"}


def _scaled3(shape, k):
    """A solid shape with every length times k."""
    s = dict(shape)
    d = dict(shape["domain"])
    for key in ("lo", "hi"):
        if key in d:
            d[key] = [k * x for x in d[key]]
    s["domain"] = d
    s["features"] = []
    for f in shape["features"]:
        g = dict(f, params={n: (k * v if n in _LENGTHS3 else v) for n, v in f["params"].items()})
        g["frame"] = dict(f["frame"], origin=[k * x for x in f["frame"]["origin"]])
        s["features"].append(g)
    return s


def _reach(shape):
    lo, hi = shape["domain"]["lo"], shape["domain"]["hi"]
    far = max(abs(x) for x in lo + hi)
    return 4 * (math.dist(lo, hi) + far)


def _occ_feature3(gmsh, f, reach):
    """The OCC volume of a 3D feature's shape (a hole's void, or a solid inclusion)."""
    occ = gmsh.model.occ
    p, t, fr = f["params"], f["type"], f["frame"]
    if t == "sphere":
        return occ.addSphere(p["cx"], p["cy"], p["cz"], p["r"])
    if t == "cylinder":
        w = fr["w"]
        length = p.get("length", 0.0) or reach
        c = [p[k] - w[i] * length / 2 for i, k in enumerate(("cx", "cy", "cz"))]
        return occ.addCylinder(*c, *(w[i] * length for i in range(3)), p["r"])
    if t == "super_ellipsoid":
        raise ValueError("feature %r: a super-ellipsoid has no exact CAD solid; STEP export "
                         "takes spheres, cylinders, pockets and through-holes" % f["name"])
    u, v, w, o = fr["u"], fr["v"], fr["w"], fr["origin"]
    p = dict(p)
    if _det3(u, v, w) < 0:  # a left-handed frame (a named face): (u, −v, w) and the profile mirrored
        v = [-x for x in v]
        p["cy"], p["angle"] = -p["cy"], -p.get("angle", 0.0)
    planar_keys = {"circle": ("cx", "cy", "r"), "ellipse": ("cx", "cy", "a", "b", "d", "angle"),
                   "super_ellipse": ("cx", "cy", "a", "b", "xi", "eta", "angle")}[f["profile"]]
    face = _occ_feature(gmsh, {"name": f["name"], "type": f["profile"],
                               "params": {k: p.get(k, 0.0) for k in planar_keys}})
    w0, w1 = -reach, (p["depth"] if t == "pocket" else reach)
    occ.translate([(2, face)], 0, 0, w0)
    volume = [tag for d, tag in occ.extrude([(2, face)], 0, 0, w1 - w0) if d == 3][0]
    # placed by rotations and a translation, which keep circles exact (a general affine map
    # turns them into approximating splines: 0.9 % of a disc's area)
    a, b, c = _zyx_angles([[u[i], v[i], w[i]] for i in range(3)])
    for angle, axis in ((c, (1, 0, 0)), (b, (0, 1, 0)), (a, (0, 0, 1))):
        if angle != 0:
            occ.rotate([(3, volume)], 0, 0, 0, *axis, angle)
    occ.translate([(3, volume)], *o)
    return volume


def _det3(u, v, w):
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
            u[2] * (v[0] * w[1] - v[1] * w[0]))


def _zyx_angles(R):
    """(a, b, c) with R = Rz(a) Ry(b) Rx(c) for a rotation matrix R (rows)."""
    b = math.asin(max(-1.0, min(1.0, -R[2][0])))
    if abs(math.cos(b)) > 1e-9:
        return math.atan2(R[1][0], R[0][0]), b, math.atan2(R[2][1], R[2][2])
    return 0.0, b, math.atan2(-R[1][2], R[1][1])


def _solid_component(gmsh, shape, notes):
    """Builds a solid design's volumes in the current Gmsh model; returns their tags."""
    if shape["domain"]["type"] != "box":
        raise ValueError("body %r: its mesh is not a box, and the part's own surface is not known "
                         "as CAD; STEP export of a solid design takes box meshes" % shape["body"])
    lo, hi = shape["domain"]["lo"], shape["domain"]["hi"]
    occ = gmsh.model.occ
    domain = occ.addBox(*lo, *(h - l for l, h in zip(lo, hi)))
    reach = _reach(shape)
    vols = _occ_region(gmsh, shape, shape["region"], domain, notes, 3,
                       lambda g, f: _occ_feature3(g, f, reach))
    occ.remove([(3, domain)], recursive=True)
    occ.synchronize()
    return [t for d, t in vols if d == 3]


def write_section_png(shape, path, axis=None, at=None, width=1200):
    """A picture of a solid design: its section by the plane across `axis` (0, 1, 2; default the
    box's thinnest direction) at `at` (default the box's middle), cut from the exact OpenCASCADE
    volume: material grey, the cut's edges black, axes in millimetres. Returns the section's
    area [m²] (the exact volume's, by Gmsh's OpenCASCADE), the figure's check against the CAD."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    shape = load_shape(shape)
    if shape.get("kind") != "solid":
        raise ValueError("write_section_png takes a solid design (a planar one: lsmbs geometry "
                         "draws it)")
    lo, hi = shape["domain"]["lo"], shape["domain"]["hi"]
    extent = [h - l for l, h in zip(lo, hi)]
    k = min(range(3), key=lambda i: extent[i]) if axis is None else axis
    if k not in (0, 1, 2):
        raise ValueError("axis %r: expected 0, 1 or 2" % (axis,))
    c = 0.5 * (lo[k] + hi[k]) if at is None else at
    if not lo[k] <= c <= hi[k]:
        raise ValueError("at %g m: outside the part's box [%g, %g] along axis %d" %
                         (c, lo[k], hi[k], k))
    u, v = [i for i in range(3) if i != k]
    with _Gmsh() as gmsh:
        occ = gmsh.model.occ
        vols = _solid_component(gmsh, shape, [])
        plane = _plane(occ, lo, hi, k, c)
        cut, _ = occ.intersect([(3, w) for w in vols], [(2, plane)], removeObject=True,
                               removeTool=True)
        occ.synchronize()
        faces = [t for d, t in cut if d == 2]
        area = sum(occ.getMass(2, t) for t in faces)
        h = max(extent[u], extent[v]) / 200
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 36)
        gmsh.model.mesh.generate(2)
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        at_node = {int(n): (1e3 * xyz[3 * i + u], 1e3 * xyz[3 * i + v]) for i, n in enumerate(tags)}
        triangles = []
        for f in faces:
            types, _, nodes = gmsh.model.mesh.getElements(2, f)
            for t, ns in zip(types, nodes):
                m = {2: 3, 3: 4}[int(t)]
                triangles += [[at_node[int(n)] for n in ns[j:j + m]] for j in range(0, len(ns), m)]
        edges = []
        for _, e in gmsh.model.getBoundary([(2, f) for f in faces], combined=False,
                                           oriented=False):
            lo_t, hi_t = gmsh.model.getParametrizationBounds(1, abs(e))
            ts = [lo_t[0] + (hi_t[0] - lo_t[0]) * j / 512 for j in range(513)]
            p = gmsh.model.getValue(1, abs(e), ts)
            edges.append(([1e3 * p[3 * j + u] for j in range(513)],
                          [1e3 * p[3 * j + v] for j in range(513)]))
    names = "xyz"
    aspect = extent[v] / extent[u]
    fig, ax = plt.subplots(figsize=(width / 100, max(2.0, width / 100 * aspect + 1.2)), dpi=100)
    ax.add_collection(PolyCollection(triangles, facecolors="0.55", edgecolors="face",
                                     linewidths=0.3))
    for xs, ys in edges:
        ax.plot(xs, ys, color="black", linewidth=0.8)
    ax.set_xlim(1e3 * lo[u], 1e3 * hi[u])
    ax.set_ylim(1e3 * lo[v], 1e3 * hi[v])
    ax.set_aspect("equal")
    ax.set_xlabel("%s [mm]" % names[u])
    ax.set_ylabel("%s [mm]" % names[v])
    ax.set_title("body %s: section %s = %.4g mm (area %.6g mm²)" %
                 (shape.get("body", ""), names[k], 1e3 * c, 1e6 * area))
    fig.tight_layout()
    fig.savefig(os.fspath(path))
    plt.close(fig)
    return area


def write_msh_solid(shape, path, size, layers=None):
    """A body-fitted hexahedral mesh (Gmsh 4.1 ASCII, metres) of a solid design whose features
    are through-holes and pockets along one edge direction k of its box (pockets machined from
    the box's faces across k): the part is then a stack of prisms, slabs between the box's faces
    and the pockets' floors. Each slab's section is the exact OpenCASCADE volume's section at the
    slab's middle; the sections, brought to one plane and fragmented together, are meshed once by
    quadrilaterals of edge about `size` (Gmsh's blossom full-quad recombination) and extruded
    slab by slab along k, so the slabs' hexahedra share their faces; the columns that are void in
    a slab (a pocket) are left out of it. `layers`: the number of layers of hexahedra along k,
    shared among the slabs by their thicknesses, at least one each (default: each slab's
    thickness over `size`). Node sets: the box's faces on which the part has surface (xmin ...
    zmax, the names a box mesh gives them), and the volume "component". Returns (path,
    {node set: surfaces}).

    The mesh is checked before it is written: hexahedra only, every quadrilateral across k convex
    and of one orientation, and the mesh's volume within 5 % of the void's of the exact one (the
    polygons inscribed in a circle of 12 segments lose 4.5 %); a size too coarse for a feature
    fails one of these, with the advice to lower it. Gmsh runs in a child process: an abort
    inside it (it has some on meshes it cannot recombine) becomes a RuntimeError."""
    shape = load_shape(shape)
    if shape.get("kind") != "solid":
        raise ValueError("write_msh_solid takes a solid design (a planar one: write_msh)")
    if not (isinstance(size, (int, float)) and math.isfinite(size) and size > 0):
        raise ValueError("size %r: expected a positive element size in metres" % (size,))
    if layers is not None and (isinstance(layers, bool) or not isinstance(layers, int)
                               or layers < 1):
        raise ValueError("layers %r: expected a whole number of at least 1" % (layers,))
    lo, hi = shape["domain"]["lo"], shape["domain"]["hi"]
    axes = set()
    for f in shape["features"]:
        if f["type"] not in ("through_hole", "pocket"):
            raise ValueError("feature %r (%s): a body-fitted hexahedral mesh is made of parts that "
                             "are prisms in slabs, whose features are all through-holes and "
                             "pockets" % (f["name"], f["type"]))
        w = f["frame"]["w"]
        k = max(range(3), key=lambda i: abs(w[i]))
        if abs(abs(w[k]) - 1) > 1e-12:
            raise ValueError("feature %r: its axis is not along an edge of the box" % f["name"])
        if f["type"] == "pocket" and min(abs(f["frame"]["origin"][k] - lo[k]),
                                         abs(f["frame"]["origin"][k] - hi[k])) > 1e-12:
            raise ValueError("feature %r: a pocket machined from inside the box, not from one of "
                             "its faces" % f["name"])
        axes.add(k)
    if len(axes) > 1:
        raise ValueError("the features run along different axes: the part is not a prism in slabs")
    k = axes.pop() if axes else 2
    extent = [h - l for l, h in zip(lo, hi)]
    if size > min(extent[i] for i in range(3) if i != k):
        raise ValueError("size %g m: above the section's smaller side (%g m)" %
                         (size, min(extent[i] for i in range(3) if i != k)))
    import multiprocessing
    ctx = multiprocessing.get_context("fork")
    queue = ctx.Queue()
    child = ctx.Process(target=_msh_solid_child, args=(queue, shape, os.fspath(path), size,
                                                       layers, k))
    child.start()
    child.join()
    if queue.empty():
        raise RuntimeError("Gmsh stopped while meshing body %r (exit code %s) at size %g m: a "
                           "feature too small or too close to another for that size; try a "
                           "smaller size" % (shape.get("body"), child.exitcode, size))
    ok, result = queue.get()
    if not ok:
        raise RuntimeError(result)
    return os.fspath(path), result


def _msh_solid_child(queue, shape, path, size, layers, k):
    """write_msh_solid's Gmsh work, in a child process: puts (True, node sets) or (False,
    message)."""
    try:
        queue.put((True, _msh_solid(shape, path, size, layers, k)))
    except Exception as e:  # noqa: BLE001 - handed to the parent
        queue.put((False, str(e)))


def _plane(occ, lo, hi, k, at):
    """A rectangle across axis k at coordinate `at`, twice the box's section on each side."""
    extent = [h - l for l, h in zip(lo, hi)]
    u, v = [i for i in range(3) if i != k]
    size = [0.0, 0.0, 0.0]
    size[u], size[v] = 2 * extent[u], 2 * extent[v]
    plane = occ.addRectangle(0, 0, 0, size[u], size[v])
    # the rectangle lies in z = 0 with sides along x and y: turn it into the (u, v) plane
    if k == 0:
        occ.rotate([(2, plane)], 0, 0, 0, 0, 1, 0, -math.pi / 2)  # z -> x, x -> -z
        occ.rotate([(2, plane)], 0, 0, 0, 1, 0, 0, math.pi / 2)
    elif k == 1:
        occ.rotate([(2, plane)], 0, 0, 0, 1, 0, 0, math.pi / 2)
    # placed by its centre (exact; OpenCASCADE pads bounding boxes by 1e-7 m)
    centre = [0.5 * (l + h) for l, h in zip(lo, hi)]
    centre[k] = at
    c = occ.getCenterOfMass(2, plane)
    occ.translate([(2, plane)], *[centre[i] - c[i] for i in range(3)])
    return plane


def _slab_levels(shape, k):
    """The box's faces across k and the pockets' floors between them, in order."""
    lo, hi = shape["domain"]["lo"], shape["domain"]["hi"]
    levels = {lo[k], hi[k]}
    for f in shape["features"]:
        if f["type"] == "pocket":
            floor = f["frame"]["origin"][k] + f["frame"]["w"][k] * f["params"]["depth"]
            if lo[k] + 1e-9 < floor < hi[k] - 1e-9:
                levels.add(floor)
    return sorted(levels)


def _msh_solid(shape, path, size, layers, k):
    lo, hi = shape["domain"]["lo"], shape["domain"]["hi"]
    u, v = [i for i in range(3) if i != k]
    levels = _slab_levels(shape, k)
    thick = [b - a for a, b in zip(levels, levels[1:])]
    if layers is None:
        counts = [max(1, round(t / size)) for t in thick]
    else:
        counts = [max(1, round(layers * t / (hi[k] - lo[k]))) for t in thick]
    with _Gmsh() as gmsh:
        occ = gmsh.model.occ
        vols = _solid_component(gmsh, shape, [])
        exact = sum(occ.getMass(3, w) for w in vols)
        if exact <= 0:
            raise RuntimeError("body %r: the design leaves no material" % shape.get("body"))
        # each slab's section at its middle, brought to the plane k = lo[k]
        sections = []
        for a, b in zip(levels, levels[1:]):
            mid = 0.5 * (a + b)
            cut, _ = occ.intersect(occ.copy([(3, w) for w in vols]), [(2, _plane(occ, lo, hi, k,
                                                                                 mid))],
                                   removeObject=True, removeTool=True)
            faces = [(d, t) for d, t in cut if d == 2]
            shift = [0.0, 0.0, 0.0]
            shift[k] = lo[k] - mid
            occ.translate(faces, *shift)
            sections.append(faces)
        occ.remove([(3, w) for w in vols], recursive=True)
        inputs = [f for faces in sections for f in faces]
        if not inputs:
            raise RuntimeError("body %r: the design leaves no material" % shape.get("body"))
        # one partition of the plane for every slab (faces of an OR region, and the slabs'
        # sections, share their edges)
        if len(inputs) > 1:
            _, children = occ.fragment(inputs[:1], inputs[1:])
        else:
            children = [inputs]
        occ.synchronize()
        material, at = [], 0
        for faces in sections:
            material.append({t for i in range(at, at + len(faces)) for _, t in children[i]})
            at += len(faces)
        columns = sorted(set().union(*material))
        current = [(2, c) for c in columns]
        keep, drop = [], []
        for j, (t, n) in enumerate(zip(thick, counts)):
            d = [0.0, 0.0, 0.0]
            d[k] = t
            out = occ.extrude(current, *d, numElements=[n], recombine=True)
            tops = [out[i - 1] for i in range(len(out)) if out[i][0] == 3]
            made = [out[i][1] for i in range(len(out)) if out[i][0] == 3]
            for c, w in zip(columns, made):
                (keep if c in material[j] else drop).append(w)
            current = tops
        if drop:
            occ.remove([(3, w) for w in drop])
        occ.synchronize()
        volumes = keep
        tol = 0.05 * min(h - l for l, h in zip(lo, hi))
        opt = gmsh.option.setNumber
        opt("Mesh.MeshSizeMax", size)
        opt("Mesh.MeshSizeMin", size / 4)
        opt("Mesh.MeshSizeFromCurvature", 12)
        opt("Mesh.Algorithm", 6)
        opt("Mesh.RecombineAll", 1)
        opt("Mesh.RecombinationAlgorithm", 3)  # blossom full-quad: no triangle is left
        opt("Mesh.ElementOrder", 1)
        opt("Mesh.MshFileVersion", 4.1)
        opt("Mesh.Binary", 0)
        found = {}
        surfaces = gmsh.model.getBoundary([(3, w) for w in volumes], combined=True,
                                          oriented=False)
        for axis, name in enumerate("xyz"):
            for side, plane in (("min", lo[axis]), ("max", hi[axis])):
                on = []
                for _, t in surfaces:
                    box = gmsh.model.getBoundingBox(2, abs(t))
                    if abs(box[axis] - plane) < tol and abs(box[axis + 3] - plane) < tol:
                        on.append(abs(t))
                if on:
                    g = gmsh.model.addPhysicalGroup(2, sorted(set(on)))
                    gmsh.model.setPhysicalName(2, g, name + side)
                    found[name + side] = sorted(set(on))
        g = gmsh.model.addPhysicalGroup(3, volumes)
        gmsh.model.setPhysicalName(3, g, "component")
        gmsh.model.mesh.generate(3)
        types, _, nodes = gmsh.model.mesh.getElements(3)
        if list(types) != [5]:  # 5: the 8-node hexahedron
            raise RuntimeError("body %r: the section's mesh kept triangles at size %g m (Gmsh "
                               "element types %s, 6 a prism): try a smaller size" %
                               (shape.get("body"), size, sorted(int(t) for t in types)))
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        at = {int(n): (xyz[3 * i + u], xyz[3 * i + v], xyz[3 * i + k]) for i, n in enumerate(tags)}
        volume, signs = 0.0, set()
        for h in nodes[0].reshape(-1, 8):
            q = [at[int(n)] for n in h[:4]]  # the source quadrilateral of an extruded hexahedron
            for i in range(4):
                a, b, c = q[i - 1], q[i], q[(i + 1) % 4]
                signs.add((b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]) > 0)
            area = 0.5 * sum(q[i][0] * q[(i + 1) % 4][1] - q[(i + 1) % 4][0] * q[i][1]
                             for i in range(4))
            volume += abs(area) * abs(at[int(h[4])][2] - q[0][2])
        void = (hi[u] - lo[u]) * (hi[v] - lo[v]) * (hi[k] - lo[k]) - exact
        if len(signs) != 1:
            raise RuntimeError("body %r: the section's mesh has quadrilaterals that are not convex "
                               "or are folded at size %g m: try a smaller size" %
                               (shape.get("body"), size))
        if abs(volume - exact) > 0.05 * void + 1e-9 * exact:
            raise RuntimeError("body %r: the mesh fills %.6g m³ where the part's volume is %.6g m³ "
                               "(%.1f %% of the void's volume off) at size %g m: a feature is too "
                               "small for that size; try a smaller size" %
                               (shape.get("body"), volume, exact, 100 * abs(volume - exact) / void,
                                size))
        gmsh.write(path)
    return found


def component_volume(shape):
    """Volume of an exported solid design [m³] (OpenCASCADE's exact volume of the Boolean
    result)."""
    shape = load_shape(shape)
    with _Gmsh() as gmsh:
        return sum(gmsh.model.occ.getMass(3, v) for v in _solid_component(gmsh, shape, []))


def _scaled(shape, k):
    """The shape with every length times k (the outline, the features' centres and sizes, the
    thickness, the node sets)."""
    lengths = {"cx", "cy", "a", "b", "r"}
    s = dict(shape)
    s["outline"] = [[[k * x, k * y] for x, y in loop] for loop in shape["outline"]]
    s["features"] = []
    for f in shape["features"]:
        g = dict(f, params={n: (k * v if n in lengths or f["type"] == "bspline" else v)
                            for n, v in f["params"].items()})
        if "control_points" in f:
            g["control_points"] = [[k * x, k * y] for x, y in f["control_points"]]
        s["features"].append(g)
    s["node_sets"] = {n: [[k * x, k * y] for x, y in pts] for n, pts in shape["node_sets"].items()}
    s["thickness"] = k * shape["thickness"]
    s["element_size"] = k * shape["element_size"]
    return s


def _node_set_curves(gmsh, faces, points, tol):
    """The boundary curves of the faces along which a node set lies: every sampled point of the
    curve within tol of the set's polyline of nodes (nearest-node distance)."""
    hits = []
    for _, c in gmsh.model.getBoundary([(2, f) for f in faces], combined=True, oriented=False):
        c = abs(c)
        if c in hits:
            continue
        lo, hi = gmsh.model.getParametrizationBounds(1, c)
        ts = [lo[0] + (hi[0] - lo[0]) * k / 16 for k in range(17)]
        xyz = gmsh.model.getValue(1, c, ts)
        if all(min(math.dist((xyz[3 * k], xyz[3 * k + 1]), q) for q in points) <= tol
               for k in range(len(ts))):
            hits.append(c)
    return hits


def write_msh(shape, path, size=None, notes=None):
    """A body-fitted mesh (Gmsh 4.1 ASCII, metres); returns (path, {node set: curves found})."""
    shape = load_shape(shape)
    h = size or shape["element_size"]
    with _Gmsh() as gmsh:
        faces = _component(gmsh, shape, [] if notes is None else notes)
        opt = gmsh.option.setNumber
        opt("Mesh.MeshSizeMax", h)
        opt("Mesh.MeshSizeMin", h / 4)
        opt("Mesh.MeshSizeFromCurvature", 12)  # about 12 elements around a full circle
        opt("Mesh.Algorithm", 6)  # frontal-Delaunay (8, for quadrilaterals, crashes Gmsh 4.8)
        opt("Mesh.RecombineAll", 1)
        opt("Mesh.ElementOrder", 1)
        opt("Mesh.MshFileVersion", 4.1)
        opt("Mesh.Binary", 0)
        found = {}
        for name, pts in sorted(shape["node_sets"].items()):
            pts = [tuple(p) for p in pts]
            gap = max((min(math.dist(p, q) for q in pts if q != p) for p in pts), default=h)
            curves = _node_set_curves(gmsh, faces, pts, 0.6 * gap + 1e-9)
            found[name] = curves
            if curves:
                g = gmsh.model.addPhysicalGroup(1, curves)
                gmsh.model.setPhysicalName(1, g, name)
        s = gmsh.model.addPhysicalGroup(2, faces)
        gmsh.model.setPhysicalName(2, s, "component")
        gmsh.model.mesh.generate(2)
        gmsh.write(os.fspath(path))
    return os.fspath(path), found


def export(shape, out_dir, formats=("dxf", "svg", "step", "msh"), size=None):
    """Writes the formats into out_dir (named after the body); returns {format: path, 'notes':
    [...], 'node_sets': {...}}."""
    shape = load_shape(shape)
    solid = shape.get("kind") == "solid"
    if solid:  # a solid design: STEP, its mid-section's picture, a body-fitted hexahedral mesh
        if formats == ("dxf", "svg", "step", "msh"):
            formats = ("step", "png")
        for fmt in formats:
            if fmt not in ("step", "png", "msh"):
                raise ValueError("format %r: a solid design is exported as STEP, png (its "
                                 "section) and msh (body-fitted hexahedra)" % fmt)
        if "msh" in formats and size is None:
            raise ValueError("format 'msh' of a solid design: give the element size")
    os.makedirs(os.fspath(out_dir), exist_ok=True)
    stem = os.path.join(os.fspath(out_dir), shape.get("body", "design"))
    out, notes = {}, []
    for fmt in formats:
        if fmt == "dxf":
            out["dxf"] = write_dxf(shape, stem + ".dxf", notes)
        elif fmt == "svg":
            out["svg"] = write_svg(shape, stem + ".svg", notes)
        elif fmt == "step":
            out["step"] = write_step(shape, stem + ".step", notes)
        elif fmt == "msh" and solid:
            out["msh"], out["node_sets"] = write_msh_solid(shape, stem + ".msh", size)
        elif fmt == "msh":
            out["msh"], out["node_sets"] = write_msh(shape, stem + ".msh", size, notes)
        elif fmt == "png" and solid:
            write_section_png(shape, stem + "_section.png")
            out["png"] = stem + "_section.png"
        else:
            raise ValueError("format %r: expected dxf, svg, step or msh" % fmt)
    out["notes"] = sorted(set(notes))
    return out


def body_fitted_case(case, body, msh, out):
    """A copy of the case file `case` in which `body` is meshed by the body-fitted `msh` (full
    material where the design has material: no design section, no optimization), written to
    `out`; mesh and table paths are made absolute. Returns the path."""
    with open(os.fspath(case)) as f:
        doc = json.load(f)
    base = os.path.dirname(os.path.abspath(os.fspath(case)))
    meshed = [b["name"] for b in doc["bodies"] if isinstance(b.get("mesh"), dict)]
    if body not in meshed:
        raise ValueError("body %r: %s has no such body with a mesh (it has %s)" %
                         (body, os.fspath(case), ", ".join(meshed) or "none"))
    for b in doc["bodies"]:
        mesh = b.get("mesh")
        if b["name"] == body:
            b["mesh"] = {"type": "gmsh", "file": os.path.abspath(os.fspath(msh)), "scale": 1.0}
        elif isinstance(mesh, dict) and "file" in mesh:
            mesh["file"] = os.path.join(base, mesh["file"])
    doc.pop("design", None)
    doc.pop("optimization", None)
    _absolute_files(doc, base)
    with open(os.fspath(out), "w") as f:
        json.dump(doc, f, indent=1)
    return os.fspath(out)


def _absolute_files(node, base):
    """Relative "file" entries (tables, initial states) made absolute against the case's folder."""
    if isinstance(node, dict):
        for k, v in node.items():
            if k == "file" and isinstance(v, str) and not os.path.isabs(v):
                node[k] = os.path.join(base, v)
            else:
                _absolute_files(v, base)
    elif isinstance(node, list):
        for v in node:
            _absolute_files(v, base)
