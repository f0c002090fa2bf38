"""VTU outputs read back with an XML parser (ParaView's format). References: the signed distance
to a circle (the design's level set φ near its boundary), and the rotation a driver prescribes to
a near-rigid plate (total displacement R(θ)X − X; elastic displacement ≈ 0)."""
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import lsmbs
from lsmbs import at, circle, rectangle

from conftest import run_cli


def read_vtu(path):
    root = ET.parse(path).getroot()
    piece = root.find("UnstructuredGrid/Piece")
    pts = np.array(piece.find("Points/DataArray").text.split(), float).reshape(-1, 3)
    arrays = {}
    for where in ("PointData", "CellData"):
        for a in piece.find(where).findall("DataArray"):
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
