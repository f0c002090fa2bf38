"""Design export (lsmbs.export: DXF, SVG, STEP, body-fitted mesh) against closed forms, on the
robot arm's initial design (robot_arm_holes.json: five ξ = 5 super-ellipses a = b = 10 mm in the
600 × 50 mm plate) and on a plate with a circle, a rotated ellipse and a notch:
  - the exported component's area (OpenCASCADE) is the plate's less the holes':
    circle π r², ellipse π a b d², super-ellipse 4 a b Γ(1 + 1/ξ)² / Γ(1 + 2/ξ), a quarter
    circle for a hole centred on a corner;
  - the DXF's CIRCLE and ELLIPSE entities carry the features' exact values (mm), the notch is an
    ARC of the COMPONENT layer, the STEP solid's volume is the area times the thickness;
  - the body-fitted mesh keeps the node sets the joints use, and lsmbs simulates it: the plate's
    mass is ρ t A.
"""
import json
import math
import os

import pytest

import lsmbs
from lsmbs import export

ezdxf = pytest.importorskip("ezdxf")
gmsh = pytest.importorskip("gmsh")

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def super_ellipse_area(a, b, xi):
    return 4 * a * b * math.gamma(1 + 1 / xi) ** 2 / math.gamma(1 + 2 / xi)


def step_volume(path):
    """The volume of the solids in a STEP file, as Gmsh's OpenCASCADE reads it back (mm³)."""
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        vols = gmsh.model.occ.importShapes(str(path))
        gmsh.model.occ.synchronize()
        return sum(gmsh.model.occ.getMass(d, t) for d, t in vols if d == 3)
    finally:
        gmsh.finalize()


def plate_shape(features):
    return {"body": "plate", "outline": [[[0, 0], [0.1, 0], [0.2, 0], [0.2, 0.05], [0, 0.05]]],
            "features": features,
            "region": {"op": "and", "ks": 0, "children": [
                {"op": "feature", "feature": k} for k in range(len(features))]},
            "node_sets": {"left": [[0, y / 100] for y in range(0, 6)]},
            "thickness": 0.002, "element_size": 0.005,
            "material": {"E": 7e10, "nu": 0.3, "rho": 2700}, "mu_min": 1e-3}


def test_exact_entities_areas_and_volume(tmp_path):
    feats = [{"name": "h1", "type": "circle", "hole": True,
              "params": {"cx": 0.05, "cy": 0.025, "r": 0.01}},
             {"name": "h2", "type": "ellipse", "hole": True,
              "params": {"cx": 0.1, "cy": 0.025, "a": 0.01, "b": 0.015, "d": 1.2, "angle": 0.4}},
             {"name": "notch", "type": "circle", "hole": True,
              "params": {"cx": 0.2, "cy": 0.05, "r": 0.012}}]
    shape = plate_shape(feats)
    exact = 0.2 * 0.05 - math.pi * 0.01 ** 2 - math.pi * 0.01 * 0.015 * 1.2 ** 2 - \
        math.pi * 0.012 ** 2 / 4
    assert export.component_area(shape) == pytest.approx(exact, rel=1e-9)
    out = export.export(shape, tmp_path, ("dxf", "svg", "step"))
    doc = ezdxf.readfile(out["dxf"])
    msp = doc.modelspace()
    circles = [e for e in msp.query("CIRCLE[layer=='FEATURES']")]
    assert sorted(round(e.dxf.radius, 9) for e in circles) == [10.0, 12.0]
    (ell,) = msp.query("ELLIPSE[layer=='FEATURES']")
    major = math.hypot(ell.dxf.major_axis.x, ell.dxf.major_axis.y)
    assert major == pytest.approx(0.015 * 1.2 * 1000, rel=1e-12)
    assert ell.dxf.ratio == pytest.approx(0.01 / 0.015, rel=1e-12)
    # the major axis (b, along the feature's v) is at angle + 90°
    assert math.atan2(ell.dxf.major_axis[1], ell.dxf.major_axis[0]) == \
        pytest.approx(0.4 + math.pi / 2, abs=1e-12)
    (arc,) = msp.query("ARC[layer=='COMPONENT']")
    assert arc.dxf.radius == pytest.approx(12.0, rel=1e-12)
    assert (arc.dxf.center[0], arc.dxf.center[1]) == pytest.approx((200.0, 50.0), abs=1e-9)
    assert (arc.dxf.start_angle % 360, arc.dxf.end_angle % 360) == pytest.approx((180, 270), abs=1e-6)
    # the hole in the middle stays whole: CIRCLE and ELLIPSE on the component's layer too
    assert len(msp.query("CIRCLE[layer=='COMPONENT']")) == 1
    assert len(msp.query("ELLIPSE[layer=='COMPONENT']")) == 1
    svg = open(out["svg"]).read()
    assert 'id="h1" cx="50" cy="25" r="10"' in svg
    # STEP: a solid of the area times the thickness (mm³)
    v = step_volume(out["step"])
    assert v == pytest.approx(exact * 0.002 * 1e9, rel=1e-9)


def test_a_mesh_with_holes_keeps_them(tmp_path):
    """A body whose mesh has holes (the rod's bores): the outline's inner loops, clockwise, are
    cut from the outer one (a face built of all the loops at once had their areas added)."""
    shape = plate_shape([{"name": "h", "type": "circle", "hole": True,
                          "params": {"cx": 0.15, "cy": 0.025, "r": 0.01}}])
    bore = [[0.04, 0.015], [0.04, 0.035], [0.06, 0.035], [0.06, 0.015]]  # clockwise
    shape["outline"].append(bore)
    exact = 0.2 * 0.05 - 0.02 * 0.02 - math.pi * 0.01 ** 2
    assert export.component_area(shape) == pytest.approx(exact, rel=1e-9)
    shape["node_sets"]["bore"] = [[0.04, 0.015 + 0.005 * k] for k in range(5)] + \
        [[0.04 + 0.005 * k, 0.035] for k in range(1, 5)] + \
        [[0.06, 0.035 - 0.005 * k] for k in range(1, 5)] + \
        [[0.06 - 0.005 * k, 0.015] for k in range(1, 4)]
    out = export.export(shape, tmp_path, ("msh",))
    assert len(out["node_sets"]["bore"]) == 4  # the bore's four edges


def test_a_non_design_ring_is_material_once(tmp_path):
    """A region OR-ed with a non-design ring around a bore (the rod's rings): the ring's material
    counts once. The hole overlaps the ring's disc: area = plate − bore − (hole − hole ∩ disc),
    with the lens of two circles in closed form (OpenCASCADE's fuse had returned the ring and the
    region whole, overlapping)."""
    shape = plate_shape([{"name": "h", "type": "circle", "hole": True,
                          "params": {"cx": 0.08, "cy": 0.025, "r": 0.012}},
                         {"name": "ring", "type": "circle", "hole": False,
                          "params": {"cx": 0.05, "cy": 0.025, "r": 0.02}}])
    shape["region"] = {"op": "or", "ks": 0, "children": [
        {"op": "and", "ks": 0, "children": [{"op": "feature", "feature": 0}]},
        {"op": "feature", "feature": 1}]}
    bore = [[0.05 + 0.008 * math.cos(-2 * math.pi * k / 64),
             0.025 + 0.008 * math.sin(-2 * math.pi * k / 64)] for k in range(64)]  # clockwise
    shape["outline"].append(bore)
    bore_area = 0.5 * 64 * 0.008 ** 2 * math.sin(2 * math.pi / 64)  # the 64-gon

    def lens(r1, r2, d):  # area of the intersection of two discs whose centres are d apart
        a1 = r1 ** 2 * math.acos((d * d + r1 * r1 - r2 * r2) / (2 * d * r1))
        a2 = r2 ** 2 * math.acos((d * d + r2 * r2 - r1 * r1) / (2 * d * r2))
        return a1 + a2 - 0.5 * math.sqrt((-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) *
                                         (d + r1 + r2))
    exact = 0.2 * 0.05 - bore_area - (math.pi * 0.012 ** 2 - lens(0.012, 0.02, 0.03))
    assert export.component_area(shape) == pytest.approx(exact, rel=1e-9)
    out = export.export(shape, tmp_path, ("dxf", "step"))
    doc = ezdxf.readfile(out["dxf"])
    assert doc.modelspace().query("*[layer=='COMPONENT']")  # one outline, read back


def test_robot_arm_design_exports_and_simulates_body_fitted(tmp_path):
    case = os.path.join(ROOT, "data/robot_arm/robot_arm_holes.json")
    cs = lsmbs.load_case(case)
    g = lsmbs.geometry(cs)["plate"]
    shape = g["shape"]
    assert [f["type"] for f in shape["features"]] == ["super_ellipse"] * 5
    assert sorted(shape["node_sets"]) == ["bottom", "left", "right", "top"]
    assert g["resolution"]["pieces"] == pytest.approx([0.6 * 0.05 - 5 * super_ellipse_area(
        0.01, 0.01, 5)], rel=2e-3)
    exact = 0.6 * 0.05 - 5 * super_ellipse_area(0.01, 0.01, 5)
    # a super-ellipse is a spline through 128 of its points: its area within 1e-3
    assert export.component_area(shape) == pytest.approx(exact, abs=5 * 1e-3 * 4e-4)
    out = export.export(shape, tmp_path, ("dxf", "msh"))
    assert out["node_sets"]["left"] and out["node_sets"]["right"]
    assert len(ezdxf.readfile(out["dxf"]).modelspace().query("SPLINE[layer=='FEATURES']")) == 5
    body_fitted = export.body_fitted_case(case, "plate", out["msh"], tmp_path / "arm_bf.json")
    r = lsmbs.simulate(lsmbs.load_case(body_fitted), out_dir=tmp_path / "sim")
    rho, t = 2700, 0.0025
    assert r.status == "complete", r.report()
    mass = r.responses["plate_mass"]
    # the mesh's polygons cut the holes' curves: the area within (chord error) 0.5 %
    assert mass == pytest.approx(rho * t * exact, rel=5e-3)
    # and the fixed mesh's mass of the same design, within what its mapping resolves (5 %)
    assert mass == pytest.approx(g["mass"], rel=5e-2)


def test_a_bspline_feature_is_exported_as_its_exact_curve(tmp_path):
    # a dented loop of 9 control points (concave parts), its curve inside the plate
    P = []
    for k in range(9):
        t = 2 * math.pi * k / 9
        r = 0.012 * (1 + 0.3 * math.cos(3 * t))
        P.append([0.1 + 1.6 * r * math.cos(t), 0.025 + r * math.sin(t)])
    feats = [{"name": "free", "type": "bspline", "hole": True, "degree": 3, "control_points": P,
              "params": {("x" if i % 2 == 0 else "y") + str(i // 2 + 1): P[i // 2][i % 2]
                         for i in range(18)}}]
    shape = plate_shape(feats)
    exact = 0.2 * 0.05 - export.bspline_area(P)
    # OpenCASCADE's area of the outline less the Bézier segments' face
    assert export.component_area(shape) == pytest.approx(exact, rel=1e-9)
    out = export.export(shape, tmp_path, ("dxf", "svg", "step"))
    # ezdxf reads back a SPLINE whose curve is the feature's: its points against ours
    (spl,) = ezdxf.readfile(out["dxf"]).modelspace().query("SPLINE[layer=='FEATURES']")
    tool = spl.construction_tool()
    assert tool.degree == 3 and len(tool.control_points) == 12
    ours = export.feature_points(feats[0], 90)
    for k, (x, y) in enumerate(ours):  # span s of ours is span s of the open spline, from t = 3
        p = tool.point(3 + 9 * k / 90)
        assert (p[0], p[1]) == pytest.approx((x * 1000, y * 1000), abs=1e-9)
    svg = open(out["svg"]).read()
    assert svg.count(" C ") == 9  # one cubic Bézier per span
    v = step_volume(out["step"])
    assert v == pytest.approx(exact * 1e6 * 2.0, rel=1e-7)


def test_a_solid_design_exports_as_its_closed_form_volume(tmp_path):
    """data/spatial/solid_arm.json's plate (`lsmbs geometry` writes plate_shape.json, "kind":
    "solid"): the STEP solid's volume, read back, is the plate's less two through-holes and the
    pocket, π r² t and the super-ellipse's area times the depth. The holes alone to 1e-6; with the
    pocket, whose profile is a spline through 128 of its points, to OpenCASCADE's integration of
    volumes bounded by spline surfaces, 1.5 % of the pocket (its prism's volume is 0.81 % above
    its face's area times its length, an area it computes to 3.5e-5): the pocket's floor, a plane
    face 4 mm below the +y face, is checked by its area instead. A super-ellipsoid is refused by
    name."""
    from conftest import run_cli
    case = os.path.join(ROOT, "data/spatial/solid_arm.json")
    run_cli("geometry", case, "-o", str(tmp_path / "g"), "--quiet")
    shape = export.load_shape(tmp_path / "g" / "plate_shape.json")
    assert shape["kind"] == "solid" and shape["domain"]["type"] == "box"
    assert [f["type"] for f in shape["features"]] == ["through_hole", "through_hole", "pocket"]
    t, r1, r2, depth = 0.01, 0.02, 0.016, 0.004
    plate, holes = 0.4 * t * 0.08, math.pi * (r1 ** 2 + r2 ** 2) * t
    pocket = super_ellipse_area(0.05, 0.025, 4) * depth
    drilled = dict(shape, features=shape["features"][:2], region={
        "op": "and", "ks": 0, "children": [{"op": "feature", "feature": k} for k in (0, 1)]})
    assert export.component_volume(drilled) == pytest.approx(plate - holes, rel=1e-6)
    assert export.component_volume(shape) == pytest.approx(plate - holes - pocket,
                                                           abs=1.5e-2 * pocket)
    out = export.export(shape, tmp_path / "cad")
    assert sorted(out) == ["notes", "png", "step"]  # a solid's default: STEP and its section
    assert step_volume(out["step"]) == pytest.approx((plate - holes - pocket) * 1e9,
                                                     abs=1.5e-2 * pocket * 1e9)  # mm³
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.occ.importShapes(str(out["step"]))
        gmsh.model.occ.synchronize()
        floor = [t for _, t in gmsh.model.getEntities(2)
                 if all(abs(y - 1.0) < 1e-6 for y in gmsh.model.getBoundingBox(2, t)[1::3])]
        assert len(floor) == 1
        assert gmsh.model.occ.getMass(2, floor[0]) == pytest.approx(pocket / depth * 1e6, rel=1e-4)
    finally:
        gmsh.finalize()
    blob = dict(shape, features=[{
        "name": "blob", "type": "super_ellipsoid", "hole": True,
        "params": {"cx": 0.2, "cy": 0, "cz": 0, "a": 0.01, "b": 0.01, "c": 0.01, "xi": 4},
        "frame": shape["features"][0]["frame"]}],
        region={"op": "feature", "feature": 0})
    with pytest.raises(ValueError, match="'blob': a super-ellipsoid has no exact CAD solid"):
        export.component_volume(blob)
    with pytest.raises(ValueError, match="a solid design is exported as STEP, png .* and msh"):
        export.export(shape, tmp_path / "cad", ("dxf",))


def test_a_solid_design_through_lsmbs_geometry_and_the_export_script(tmp_path):
    """The two other routes to a solid design's CAD: lsmbs.geometry(case)["plate"] carries the
    same shape as the file `lsmbs geometry` writes, with the mass ρ0 Σ μ_e V_e and its gradient
    (against central differences of the mass over the variables' values, and the closed-form
    volume within the band's bias); scripts/export_design.py writes the STEP of a solid shape
    (its default formats become step) and refuses a planar format for it with exit 2."""
    import subprocess
    import sys
    from conftest import run_cli
    case_file = os.path.join(ROOT, "data/spatial/solid_arm.json")
    run_cli("geometry", case_file, "-o", str(tmp_path / "g"), "--quiet")
    written = export.load_shape(tmp_path / "g" / "plate_shape.json")
    case = lsmbs.load_case(case_file)
    g = lsmbs.geometry(case)["plate"]
    assert g["shape"]["features"] == written["features"]
    assert g["nodes"].shape == (21 * 3 * 5, 3) and set(g["cell_types"]) == {"hex8"}
    t, r1, r2, depth = 0.01, 0.02, 0.016, 0.004
    volume = 0.4 * t * 0.08 - math.pi * (r1 ** 2 + r2 ** 2) * t - super_ellipse_area(0.05, 0.025, 4) * depth
    assert g["mass"] == pytest.approx(2700 * volume, rel=2e-3)
    # the resolution: one piece, its volume that of the samples in material (5 mm apart across
    # the thickness: the 4 mm pocket counts as 5 mm deep, 1.7 % of the volume)
    assert len(g["resolution"]["pieces"]) == 1
    assert g["resolution"]["pieces"][0] == pytest.approx(volume, rel=0.025)
    # central differences: the floor's band is thin in depth (μ's third derivative there is
    # large), so its step is 1e-8 (measured: 3.6e-6 off at 1e-6, 4e-8 at 1e-7, 7e-9 at 1e-8)
    p0 = [r1, r2, depth]
    for j, h in enumerate((1e-6, 1e-6, 1e-8)):
        up, down = list(p0), list(p0)
        up[j] += h
        down[j] -= h
        fd = (lsmbs.geometry(case, up)["plate"]["mass"] -
              lsmbs.geometry(case, down)["plate"]["mass"]) / (2 * h)
        assert g["mass_gradient"][j] == pytest.approx(fd, rel=1e-6)
    script = os.path.join(ROOT, "scripts/export_design.py")
    p = subprocess.run([sys.executable, script, str(tmp_path / "g" / "plate_shape.json"), "-o",
                        str(tmp_path / "cad")], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert step_volume(tmp_path / "cad" / "plate.step") == pytest.approx(
        volume * 1e9, rel=1.5e-2 * super_ellipse_area(0.05, 0.025, 4) * depth / volume)
    p = subprocess.run([sys.executable, script, str(tmp_path / "g" / "plate_shape.json"), "-o",
                        str(tmp_path / "cad2"), "--formats", "dxf"], capture_output=True, text=True)
    assert p.returncode == 2 and "dxf not written for a solid body's design" in p.stderr
    assert (tmp_path / "cad" / "plate_section.png").stat().st_size > 10_000
    p = subprocess.run([sys.executable, script, str(tmp_path / "g" / "plate_shape.json"), "-o",
                        str(tmp_path / "cad3"), "--formats", "msh"], capture_output=True, text=True)
    assert p.returncode == 2 and "needs --size" in p.stderr


def test_a_through_hole_design_meshes_body_fitted_in_hexahedra(tmp_path):
    """lsmbs.export.write_msh_solid: solid_arm.json's plate with its two drilled holes meshed by
    quadrilaterals on its section and extruded in two layers of hexahedra (and, with its pocket,
    in two slabs: under the pocket's floor and beside the pocket; test below); a sphere, which
    makes no prism, is refused. References: the closed-form volume
    (plate less π r² t per hole; the mesh's polygons inscribed in the circles remove less, by at
    most 1 - sin(2π/n)/(2π/n) of the holes for n ≥ 12 segments, 4.5 %) and the mass lsmbs
    integrates over the mesh (ρ times the mesh's own volume, the extruded quads' areas times the
    thickness). Every element is an 8-node hexahedron, the box's faces the part touches are
    node sets, and the case runs with the mesh in place of the box."""
    from conftest import run_cli
    case = os.path.join(ROOT, "data/spatial/solid_arm.json")
    run_cli("geometry", case, "-o", str(tmp_path / "g"), "--quiet")
    shape = export.load_shape(tmp_path / "g" / "plate_shape.json")
    drilled = dict(shape, features=shape["features"][:2], region={
        "op": "and", "ks": 0, "children": [{"op": "feature", "feature": k} for k in (0, 1)]})
    ball = dict(shape, features=shape["features"] + [dict(
        shape["features"][0], name="ball", type="sphere",
        params={"cx": 0.3, "cy": 0, "cz": 0, "r": 0.003})])
    with pytest.raises(ValueError, match="'ball' \\(sphere\\): .* through-holes and pockets"):
        export.write_msh_solid(ball, tmp_path / "no.msh", 0.004)
    for size, layers in ((0, 1), (float("nan"), 1), (0.004, 0), (0.004, 2.5)):
        with pytest.raises(ValueError, match="expected a (positive element size|whole number)"):
            export.write_msh_solid(drilled, tmp_path / "no.msh", size, layers)
    # a hole far smaller than the size: refused with the advice, never a wrong mesh or an abort
    pin = json.loads(json.dumps(drilled))
    pin["features"][0]["params"]["r"] = 0.001
    with pytest.raises(RuntimeError, match="try a smaller size"):
        export.write_msh_solid(pin, tmp_path / "no.msh", 0.01)
    msh, sets = export.write_msh_solid(drilled, tmp_path / "plate.msh", 0.004, layers=2)
    assert {"xmin", "xmax"} <= set(sets) and all(sets.values())
    t, r1, r2 = 0.01, 0.02, 0.016
    plate, holes = 0.4 * t * 0.08, math.pi * (r1 ** 2 + r2 ** 2) * t
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(msh))
        types, _, nodes = gmsh.model.mesh.getElements(3)
        assert list(types) == [5]  # 8-node hexahedra only
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        at = {int(k): xyz[3 * i:3 * i + 3] for i, k in enumerate(tags)}
        w = drilled["features"][0]["frame"]["w"]
        k = max(range(3), key=lambda i: abs(w[i]))  # the holes' axis: the extrusion's
        u, v = [i for i in range(3) if i != k]
        volume = 0.0
        hexes = nodes[0].reshape(-1, 8)
        for h in hexes:  # an extruded hexahedron: its bottom quad's area times its height
            q = [at[int(n)] for n in h[:4]]
            assert max(abs(p[k] - q[0][k]) for p in q) < 1e-12  # the quad lies across the axis
            area = 0.5 * abs(sum(q[i][u] * q[i - 3][v] - q[i - 3][u] * q[i][v] for i in range(4)))
            volume += area * abs(at[int(h[4])][k] - q[0][k])
    finally:
        gmsh.finalize()
    assert len(hexes) > 2 * 0.4 * 0.08 / 0.004 ** 2 * 0.5  # two layers of about h-sized quads
    removed = plate - volume
    print("body-fitted hexahedra: %d, removed %.5f of the holes' closed-form volume" %
          (len(hexes), removed / holes))
    assert holes * (1 - 0.045) <= removed <= holes * (1 + 1e-9)
    doc = json.loads(open(case).read())
    bf = export.body_fitted_case(case, "plate", msh, tmp_path / "bf.json")
    out = tmp_path / "bf_run"
    summary = run_cli("simulate", bf, "-o", str(out), "--set", "/simulation/t_end=0.002")
    assert summary["responses"]["plate_mass"] == pytest.approx(
        doc["bodies"][[b["name"] for b in doc["bodies"]].index("plate")]["material"]["rho"]
        * volume, rel=1e-10)


def test_a_pocketed_design_meshes_body_fitted_in_slabs_of_hexahedra(tmp_path):
    """write_msh_solid on solid_arm.json's whole design: two holes through the 10 mm plate and a
    super-ellipse pocket (a = 50, b = 25 mm, ξ = 4) machined 4 mm deep from its +y face. The part
    is two slabs, 6 mm under the pocket's floor and 4 mm beside the pocket, meshed by one
    partition of the section extruded through both: hexahedra only, nodes on the floor's plane
    (y = 1 mm), and the volume removed that of the holes and the pocket in closed form
    (4ab Γ(1 + 1/ξ)²/Γ(1 + 2/ξ) · depth), less the polygons' 4.5 % at most."""
    from conftest import run_cli
    case = os.path.join(ROOT, "data/spatial/solid_arm.json")
    run_cli("geometry", case, "-o", str(tmp_path / "g"), "--quiet")
    shape = export.load_shape(tmp_path / "g" / "plate_shape.json")
    msh, sets = export.write_msh_solid(shape, tmp_path / "plate.msh", 0.004)
    assert {"xmin", "xmax", "ymin", "ymax"} <= set(sets)
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(msh))
        types, _, nodes = gmsh.model.mesh.getElements(3)
        assert list(types) == [5]
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        at = {int(k): xyz[3 * i:3 * i + 3] for i, k in enumerate(tags)}
        used = {int(n) for n in nodes[0]}
        assert any(abs(at[n][1] - 0.001) < 1e-9 for n in used), "a layer at the pocket's floor"
        volume = 0.0
        for h in nodes[0].reshape(-1, 8):
            q = [at[int(n)] for n in h[:4]]
            area = 0.5 * abs(sum(q[i][0] * q[i - 3][2] - q[i - 3][0] * q[i][2] for i in range(4)))
            volume += area * abs(at[int(h[4])][1] - q[0][1])
    finally:
        gmsh.finalize()
    t, r1, r2, depth = 0.01, 0.02, 0.016, 0.004
    voids = math.pi * (r1 ** 2 + r2 ** 2) * t + super_ellipse_area(0.05, 0.025, 4) * depth
    removed = 0.4 * t * 0.08 - volume
    print("slabs of hexahedra: removed %.5f of the voids' closed-form volume" % (removed / voids))
    assert voids * (1 - 0.045) <= removed <= voids * (1 + 1e-9)


def test_a_solid_design_is_drawn_as_its_exact_section(tmp_path):
    """lsmbs.export.write_section_png: solid_arm.json's plate (0.4 x 0.01 x 0.08 m, holes of
    r = 20 and 16 mm through its 10 mm thickness at x = 100 and 200 mm, a super-ellipse pocket
    of 100 x 50 mm and 4 mm deep in its +y face) cut by three planes; the returned area is the
    exact volume's section, against closed forms: the mid-plane y = 0 misses the pocket (plate
    less two discs); x = 200 mm crosses hole 2 along its diameter; z = 0 crosses both holes'
    diameters and the pocket's length."""
    from conftest import run_cli
    run_cli("geometry", os.path.join(ROOT, "data/spatial/solid_arm.json"), "-o",
            str(tmp_path / "g"), "--quiet")
    shape = tmp_path / "g" / "plate_shape.json"
    t, w, r1, r2, depth, a = 0.01, 0.08, 0.02, 0.016, 0.004, 0.05
    # exact circles to 1e-6; the pocket's profile is a spline through 128 points of the
    # super-ellipse, whose length along its axis it gives to 2e-5 m here (7e-5 of the section)
    cases = {(None, None): (0.4 * w - math.pi * (r1 ** 2 + r2 ** 2), 1e-6),  # thinnest: y
             (0, 0.2): (t * w - 2 * r2 * t, 1e-6),
             (2, 0.0): (0.4 * t - 2 * (r1 + r2) * t - 2 * a * depth, 1e-4)}
    for (axis, at), (exact, rel) in cases.items():
        png = tmp_path / ("section_%s.png" % axis)
        area = export.write_section_png(shape, png, axis=axis, at=at)
        assert area == pytest.approx(exact, rel=rel), (axis, at)
        assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(ValueError, match="outside the part's box"):
        export.write_section_png(shape, tmp_path / "no.png", axis=0, at=0.5)
