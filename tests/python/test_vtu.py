"""VTU outputs read back with an XML parser (ParaView's format). References: the signed distance
to a circle (the design's level set φ near its boundary), the rotation a driver prescribes to
a near-rigid plate (total displacement R(θ)X − X; elastic displacement ≈ 0), the bodies of the case
(every one in every multiblock), the convex hull of a rigid body's joint points, and the crank of a
four-bar (its driven pin). test_vtk_reader.py reads the same files with VTK itself."""
import math
import subprocess
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import lsmbs
from lsmbs import at, circle, rectangle

import fourbar
from conftest import CLI, run_cli


def read_vtu(path):
    root = ET.parse(path).getroot()
    piece = root.find("UnstructuredGrid/Piece")
    pts = np.array(piece.find("Points/DataArray").text.split(), float).reshape(-1, 3)
    arrays = {}
    for where in ("PointData", "CellData"):
        for a in piece.findall(where + "/DataArray"):
            v = np.array(a.text.split(), float)
            n = int(a.get("NumberOfComponents", "1"))
            arrays[a.get("Name")] = v.reshape(-1, n) if n > 1 else v
    return pts, arrays


def test_design_vtu_has_phi_and_mu_only_and_phi_is_the_distance_to_the_hole(tmp_path):
    m = lsmbs.ModelBuilder("plate")
    m.flexible_body("plate", rectangle((0, 0), (0.2, 0.1), (20, 10)), E=70e9, nu=0.3, rho=2700,
                    thickness=0.001)
    m.clamp("c", "plate", "left")
    r = m.variable("r", 0.03, 0.01, 0.04)
    m.features("plate", [circle("h", 0.1, 0.05, r)])
    m.simulation(t_end=0.01, h=0.01)
    m.save(tmp_path / "plate.json")
    run_cli("geometry", tmp_path / "plate.json", "-o", tmp_path / "geo")
    pts, arrays = read_vtu(tmp_path / "geo" / "plate.vtu")
    assert set(arrays) == {"phi", "mu"}  # no placeholder displacement or stress
    d = np.hypot(pts[:, 0] - 0.1, pts[:, 1] - 0.05) - 0.03
    near = np.abs(d) < 0.015
    assert near.sum() > 20
    assert np.max(np.abs(arrays["phi"][near] - d[near])) < 1e-12
    assert np.all(np.sign(arrays["phi"][np.abs(d) > 1e-9]) == np.sign(d[np.abs(d) > 1e-9]))
    assert arrays["mu"].min() == pytest.approx(1e-3) and arrays["mu"].max() == 1.0


def test_simulation_vtu_separates_the_rigid_motion_from_the_elastic_one(tmp_path):
    # a very stiff plate on a hub turned by a quarter turn: the plate moves (almost) rigidly
    m = lsmbs.ModelBuilder("turned_plate")
    m.rigid_body("hub", mass=1, inertia=0.01)
    m.flexible_body("plate", rectangle((0, -0.02), (0.3, 0.04), (15, 2)), E=7e15, nu=0.3,
                    rho=2700, thickness=0.002)
    m.revolute("axis", at("hub"))
    law = lsmbs.trapezoid(0, math.pi / 2, acceleration=20, speed=4)
    m.rotation_driver("turn", "hub", law)
    m.rigid_connection("root", "hub", "plate", "left")
    m.measure("angle", "angle", body="hub")
    m.response("final_angle", "angle", "final")
    m.output(vtu_stride=50)
    m.simulation(t_end=1.0, h=0.005)
    m.save(tmp_path / "turn.json")
    S = run_cli("simulate", tmp_path / "turn.json", "-o", tmp_path / "sim")
    th = S["responses"]["final_angle"]
    assert th == pytest.approx(math.pi / 2, abs=1e-9)
    pvd = ET.parse(tmp_path / "sim" / "plate.pvd").getroot()
    t, last = max((float(d.get("timestep")), d.get("file")) for d in pvd.iter("DataSet"))
    assert t == pytest.approx(1.0)
    pts, arrays = read_vtu(tmp_path / "sim" / last)
    X = pts[:, :2] - arrays["total_displacement"][:, :2]  # reference positions
    R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    rigid = X @ R.T - X
    assert np.max(np.abs(arrays["total_displacement"][:, :2] - rigid)) < 1e-6
    assert np.max(np.abs(rigid)) > 0.3  # the tip moved by 0.3 √2 m
    assert np.max(np.abs(arrays["elastic_displacement"])) < 1e-6


def test_elastic_displacement_is_the_motion_left_after_the_best_fitting_rigid_motion(tmp_path):
    # a soft plate turned by the hub bends; reference: Kabsch's SVD solution of the same
    # least-squares fit, computed here from the VTU's points and total displacement
    m = lsmbs.ModelBuilder("soft_plate")
    m.rigid_body("hub", mass=1, inertia=0.01)
    m.flexible_body("plate", rectangle((0, -0.02), (0.3, 0.04), (15, 2)), E=7e8, nu=0.3,
                    rho=2700, thickness=0.002)
    m.revolute("axis", at("hub"))
    m.rotation_driver("turn", "hub", lsmbs.trapezoid(0, 1.0, acceleration=40, speed=8))
    m.rigid_connection("root", "hub", "plate", "left")
    m.output(vtu_stride=10)
    m.simulation(t_end=0.1, h=0.005)
    m.save(tmp_path / "soft.json")
    run_cli("simulate", tmp_path / "soft.json", "-o", tmp_path / "sim")
    pvd = ET.parse(tmp_path / "sim" / "plate.pvd").getroot()
    _, last = max((float(d.get("timestep")), d.get("file")) for d in pvd.iter("DataSet"))
    pts, arrays = read_vtu(tmp_path / "sim" / last)
    x = pts[:, :2]
    X = x - arrays["total_displacement"][:, :2]
    a, b = X - X.mean(0), x - x.mean(0)
    U, _, Vt = np.linalg.svd(a.T @ b)
    R = (U @ Vt).T
    if np.linalg.det(R) < 0:
        raise AssertionError("reflection")
    elastic = x - (x.mean(0) + a @ R.T)
    assert np.max(np.abs(elastic)) > 1e-5  # the plate bends (4.7e-5 m at the tip)
    assert np.max(np.abs(arrays["elastic_displacement"][:, :2] - elastic)) < 1e-9


def cell_types(path):
    piece = ET.parse(path).getroot().find("UnstructuredGrid/Piece")
    return [int(x) for x in piece.find("Cells/DataArray[@Name='types']").text.split()]


def test_every_multiblock_lists_every_body_and_every_file_is_in_the_summary(tmp_path):
    m, _ = fourbar.build()
    m.save(tmp_path / "fourbar.json")
    S = run_cli("simulate", tmp_path / "fourbar.json", "-o", tmp_path / "out")
    out = tmp_path / "out"
    written = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert written == S["files"]  # every file written is listed, and nothing else
    pvd = ET.parse(out / "model.pvd").getroot()
    steps = [(float(d.get("timestep")), d.get("file")) for d in pvd.iter("DataSet")]
    assert len(steps) == 5  # steps 0, 25, …, 100
    for t, f in steps:
        vtm = ET.parse(out / f).getroot()
        assert vtm.get("type") == "vtkMultiBlockDataSet"
        ds = {d.get("name"): (out / f).parent / d.get("file") for d in vtm.iter("DataSet")}
        assert set(ds) == {"crank", "coupler", "rocker"}
        assert all(p.is_file() for p in ds.values())
        # the crank's line ends at its ground pivot and at the pin the driver puts at θ2(t)
        pts, arrays = read_vtu(ds["crank"])
        a, _ = fourbar.joints(fourbar.crank_angle(t))
        assert cell_types(ds["crank"]) == [3]  # VTK_LINE
        assert np.max(np.abs(pts[:, :2] - np.array([[0, 0], a]))) < 1e-10
        assert set(arrays) == {"total_displacement", "elastic_displacement"}
        assert cell_types(ds["coupler"]) == [9] * (fourbar.NX * fourbar.NY)  # VTK_QUAD
    # each body's own series too
    for body in ("crank", "coupler", "rocker"):
        files = [d.get("file") for d in ET.parse(out / f"{body}.pvd").getroot().iter("DataSet")]
        assert len(files) == 5 and all(f.startswith(f"vtu/{body}_") for f in files)


def test_a_rigid_body_is_drawn_as_the_convex_hull_of_its_attachment_points(tmp_path):
    # a triangular plate on a pivot, held by springs at two corners; a spring at a point on the
    # edge between the pivot and a corner (collinear: not a hull vertex); a lone block (nothing
    # attached: a vertex at its reference point)
    m = lsmbs.ModelBuilder("triangle")
    m.rigid_body("plate", position=(1, 2), angle=0.3, mass=1, inertia=0.01)
    m.rigid_body("block", position=(3, 0), mass=1)
    m.revolute("pivot", at("plate"))
    m.spring_damper("s1", at("plate", (0.4, 0)), lsmbs.ground((2, 2)), stiffness=10)
    m.spring_damper("s2", at("plate", (0.1, 0.3)), lsmbs.ground((1, 3)), stiffness=10)
    m.spring_damper("s3", at("plate", (0.2, 0)), lsmbs.ground((1.5, 1)), stiffness=10)
    m.output(vtu_stride=1)
    m.simulation(t_end=0.01, h=0.01)
    m.save(tmp_path / "tri.json")
    S = run_cli("static", tmp_path / "tri.json", "-o", tmp_path / "st")
    assert {"model.vtm", "plate.vtu", "block.vtu"} <= set(S["files"])
    vtm = ET.parse(tmp_path / "st" / "model.vtm").getroot()
    assert {d.get("name") for d in vtm.iter("DataSet")} == {"plate", "block"}
    pts, arrays = read_vtu(tmp_path / "st" / "plate.vtu")
    assert cell_types(tmp_path / "st" / "plate.vtu") == [7]  # VTK_POLYGON
    # at t = 0 (points − total displacement): the corners placed at (1, 2) turned by 0.3 rad
    X = pts[:, :2] - arrays["total_displacement"][:, :2]
    c, s_ = math.cos(0.3), math.sin(0.3)
    corners = np.array([[0, 0], [0.4, 0], [0.1, 0.3]]) @ np.array([[c, -s_], [s_, c]]).T + (1, 2)
    assert len(X) == 3
    for k in range(3):  # the same triangle, counter-clockwise from any vertex
        if np.allclose(np.roll(X, k, axis=0), corners, atol=1e-12):
            break
    else:
        raise AssertionError(X)
    pts, _ = read_vtu(tmp_path / "st" / "block.vtu")
    assert cell_types(tmp_path / "st" / "block.vtu") == [1]  # VTK_VERTEX
    assert np.allclose(pts[:, :2], [[3, 0]], atol=1e-12)


@pytest.mark.parametrize("name, stem", [("model", "model_2"), ("a/b", "a_b"),
                                        (".hidden", "_hidden"), ("../up", "_._up"),
                                        ("x\nsystem 'touch MARK'", "x_system__touch_MARK_")])
def test_a_body_name_is_data_and_its_files_are_named_by_a_safe_stem(tmp_path, name, stem):
    """Any text names a body: its files are named by the stem of docs/case-format.md (letters,
    digits, '-', '_', '.'; others '_'; no leading '.'; distinct from 'model'), inside the output
    folder; the multiblock file names the block by the body's own name."""
    import xml.etree.ElementTree as ET
    m = lsmbs.ModelBuilder("named")
    m.rigid_body(name, mass=1, inertia=1)
    m.output(vtu_stride=1)
    m.simulation(t_end=0.01, h=0.01)
    (tmp_path / "c.json").write_text(__import__("json").dumps(m.document()))
    p = subprocess.run([CLI, "simulate", str(tmp_path / "c.json"), "-o", str(tmp_path / "o"), "-q"],
                       capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    S = __import__("json").loads((tmp_path / "o" / "summary.json").read_text())
    assert f"{stem}.pvd" in S["files"] and (tmp_path / "o" / f"{stem}.pvd").is_file()
    assert sorted(x.name for x in tmp_path.iterdir()) == ["c.json", "o"]  # nothing outside
    blocks = ET.parse(tmp_path / "o" / "vtu" / "model_0.vtm").getroot().iter("DataSet")
    assert [(b.get("name"), b.get("file")) for b in blocks] == [
        (name.replace("\n", "\ufffd"), f"{stem}_0.vtu")]  # XML 1.0 has no control characters


def test_a_spatial_body_is_drawn_in_3d_where_its_measures_put_it_and_stays_rigid(tmp_path):
    """The spatial slider-crank ("dimension": 3) with VTU output: each body's first point is its
    centre of mass, at the position the history's measure gives at that step (slider), and the
    distances between a body's drawn points do not change (a rigid body; z is written)."""
    import json
    from conftest import ROOT
    doc = json.loads((ROOT / "data/spatial/slider_crank_spatial.json").read_text())
    doc["output"]["vtu_stride"] = 100
    case = tmp_path / "case.json"
    case.write_text(json.dumps(doc))
    out = tmp_path / "out"
    run_cli("simulate", case, "-o", out)
    hist = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    first = None
    for step in (0, 100, 200, 300, 400):
        pts, arrays = read_vtu(out / "vtu" / f"slider_{step}.vtu")
        row = hist[step]
        assert np.allclose(pts[0], [row["sliderx"], row["slidery"], row["sliderz"]], atol=1e-12)
        rod, _ = read_vtu(out / "vtu" / f"rod_{step}.vtu")
        gaps = np.linalg.norm(rod[:, None, :] - rod[None, :, :], axis=2)
        if first is None:
            first = gaps
            assert np.ptp(rod[:, 2]) > 0.01  # drawn in 3D: the rod's axes leave the plane z = 0
        assert np.allclose(gaps, first, atol=1e-9)
    assert set(arrays) == {"elastic_displacement", "total_displacement", "part"}


def test_a_solid_body_is_drawn_as_hexahedra_where_its_measures_put_it(tmp_path):
    """data/spatial/solid_cantilever.json with VTU output: 20 hexahedra (VTK type 12) on the
    deformed nodes; the tip face's mean height is the history's node_set_position; the total
    displacement is the node's motion from t = 0 (zero at the clamp), the elastic one that motion
    less a rigid fit (here, a cantilever bending: most of it)."""
    import json
    from conftest import ROOT
    doc = json.loads((ROOT / "data/spatial/solid_cantilever.json").read_text())
    doc["output"]["vtu_stride"] = 50
    case = tmp_path / "case.json"
    case.write_text(json.dumps(doc))
    out = tmp_path / "out"
    run_cli("simulate", case, "-o", out)
    hist = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    x0, _ = read_vtu(out / "vtu" / "beam_0.vtu")
    tip = np.isclose(x0[:, 0], 10.0)
    root = np.isclose(x0[:, 0], 0.0)
    assert tip.sum() == 4 and root.sum() == 4
    for step in (50, 100, 150):
        pts, arrays = read_vtu(out / "vtu" / f"beam_{step}.vtu")
        assert np.isclose(pts[tip, 2].mean(), hist[step]["tipz"], atol=1e-14, rtol=0)
        total = arrays["total_displacement"]
        assert np.allclose(total, pts - x0, atol=1e-12)
        assert np.abs(total[root]).max() < 1e-12
        assert set(arrays) == {"elastic_displacement", "total_displacement", "mu", "von_mises"}
        assert np.all(arrays["mu"] == 1.0) and np.all(arrays["von_mises"] >= 0)
    cells = ET.parse(out / "vtu" / "beam_50.vtu").getroot().find("UnstructuredGrid/Piece/Cells")
    types = next(a for a in cells.findall("DataArray") if a.get("Name") == "types")
    assert [int(t) for t in types.text.split()] == [12] * 20
