"""Planar cases written as spatial ones (lsmbs.planar.to_spatial, scripts/planar_to_spatial.py).

Reference: the planar case itself. Natural coordinates and planar angles are two discretizations
of the same equations of motion, so the two agree to the integrator's O(h²), not to round-off
(docs/methods.md, "Spatial rigid bodies"): halving h must divide the difference of every response
and every gradient entry by 4 (a fitted order within 2 ± 0.3), and both converge to one limit.
"""
import json
import math
import subprocess
import sys

import numpy as np
import pytest

import lsmbs
from lsmbs.planar import to_spatial

from conftest import ROOT

CASES = {
    # case, step sizes, the responses' and gradients' worst relative difference allowed at h
    "andrews": (ROOT / "data/andrews/andrews_squeezer.json", 4e-5),
    "slider_crank_spring": (ROOT / "data/slider_crank_rigid/slider_crank_spring.json", 1e-3),
}


def run(path, h):
    case = lsmbs.load_case(str(path))
    case.simulation.h = h
    r = lsmbs.sensitivity(case, method="direct-analytic")
    return r.values, r.gradients


def differences(planar, spatial):
    """Per response: max |difference of the values| and of the gradient entries."""
    (v2, g2), (v3, g3) = planar, spatial
    return {k: (float(np.abs(np.asarray(v3[k]) - np.asarray(v2[k])).max()),
                float(np.abs(g3[k] - g2[k]).max())) for k in v2}


@pytest.mark.parametrize("name", sorted(CASES))
def test_a_planar_case_written_in_3d_converges_to_the_planar_results(name, tmp_path):
    src, h = CASES[name]
    doc = json.loads(src.read_text())
    doc3, notes = to_spatial(doc, source=src.name)
    path3 = tmp_path / f"{name}_3d.json"
    path3.write_text(json.dumps(doc3))
    planar = [run(src, hh) for hh in (h, h / 2)]
    d = [differences(p, run(path3, hh)) for p, hh in zip(planar, (h, h / 2))]
    aggregate = {r["name"]: r["aggregate"] for r in doc["output"]["responses"]}
    for k, (dv, dg) in d[0].items():
        dv2, dg2 = d[1][k]
        print(f"{name} {k}: |3D − 2D| value {dv:.2e} -> {dv2:.2e}, gradient {dg:.2e} -> {dg2:.2e}")
        for (a, b, which) in ((dv, dv2, 0), (dg, dg2, 1)):
            if aggregate[k].startswith("average"):
                # the sample mean over the steps is an O(h) time average in both models: their
                # common first-order error cancels in the difference and leaves mixed terms, so
                # no order; the difference stays below the planar model's own change from h to
                # h/2 (its discretization error)
                own = float(np.abs(np.asarray(planar[0][which][k]) -
                                   np.asarray(planar[1][which][k])).max())
                assert b < own, (k, b, own)
            else:  # the difference of two O(h²) discretizations of the same equations
                order = math.log2(a / b)
                assert 1.7 < order < 2.3, (k, a, b, order)


def test_the_converter_says_what_it_cannot_write(tmp_path):
    robot = json.loads((ROOT / "data/robot_arm/robot_arm.json").read_text())
    with pytest.raises(ValueError, match=r"/bodies/2: a flexible body has no spatial counterpart"):
        to_spatial(robot)
    doc = json.loads((ROOT / "data/slider_crank_rigid/slider_crank_spring.json").read_text())
    doc["forces"].append({"name": "m", "type": "point_mass", "mass": 1,
                          "point": {"body": "rod", "at": [0.1, 0]}})
    with pytest.raises(ValueError, match=r"/forces/1: a point_mass force has no spatial"):
        to_spatial(doc)
    # the command line: exit 2 with the file and the JSON path, and no file written
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(robot))
    out = tmp_path / "out.json"
    p = subprocess.run([sys.executable, str(ROOT / "scripts/planar_to_spatial.py"), str(bad), "-o",
                        str(out)], capture_output=True, text=True)
    assert p.returncode == 2 and "bad.json: /bodies/2" in p.stderr, p.stderr
    assert not out.exists()


def test_a_loop_is_closed_by_an_inline_joint_and_angles_are_sums_of_joint_angles():
    doc = json.loads((ROOT / "data/andrews/andrews_squeezer.json").read_text())
    doc3, notes = to_spatial(doc)
    kinds = [j["type"] for j in doc3["joints"]]
    # 7 bodies, 10 revolute joints: a tree of 7 revolutes, and 3 loops closed by inline joints
    assert kinds.count("revolute") == 7 and kinds.count("inline") == 3
    # Grübler in space: 6 × 7 − (5 × 7 + 2 × 3) = 1 degree of freedom, as in the plane
    assert 6 * 7 - (5 * 7 + 2 * 3) == 1
    th3 = next(m for m in doc3["output"]["measures"] if m["name"] == "th3")
    assert th3["type"] == "combination" and th3["constant"] == doc["bodies"][2]["angle"]
    assert notes == ["left out measure 'spring_length' (distance): no spatial counterpart here, "
                     "and no response uses it"]


def pendulum(**body):
    """A pendulum pinned at the origin, its reference point at (1, 0)."""
    b = {"name": "bob", "type": "rigid", "position": [1, 0], "mass": 1, "inertia": 0.1}
    b.update(body)
    return {"name": "pend", "gravity": [0, -9.81], "bodies": [b],
            "joints": [{"name": "pin", "type": "revolute", "a": {"body": "bob", "at": [-1, 0]}}],
            "simulation": {"t_end": 0.5, "h": 0.005},
            "output": {"measures": [{"name": "bob", "type": "position", "point": {"body": "bob"}},
                                    {"name": "pin_force", "type": "constraint_force",
                                     "joint": "pin"}],
                       "responses": [{"name": "y_end", "measure": "bob.y", "aggregate": "final"}]}}


def four_bar(closing_last):
    """A driven four-bar whose joint listed last closes the loop: O2, B, O4, A (A between the
    coupler and the crank, two moving bodies) or O2, A, B, O4 (O4 to the ground)."""
    bodies = [{"name": "crank", "type": "rigid", "position": [0, 0], "mass": 1, "inertia": 0.01},
              {"name": "coupler", "type": "rigid", "position": [0.1, 0], "mass": 1,
               "inertia": 0.02},
              {"name": "rocker", "type": "rigid", "position": [0.3, 0], "mass": 1,
               "inertia": 0.01}]
    j = {"O2": {"name": "O2", "type": "revolute", "a": {"body": "crank"}},
         "A": {"name": "A", "type": "revolute", "a": {"body": "crank", "at": [0.1, 0]},
               "b": {"body": "coupler"}},
         "B": {"name": "B", "type": "revolute", "a": {"body": "coupler", "at": [0.3, 0.2]},
               "b": {"body": "rocker", "at": [0.1, 0.2]}},
         "O4": {"name": "O4", "type": "revolute", "a": {"body": "rocker"}}}
    order = ["O2", "B", "O4", "A"] if closing_last == "A" else ["O2", "A", "B", "O4"]
    return {"name": "fb", "bodies": bodies, "joints": [j[k] for k in order] + [
        {"name": "motor", "type": "rotation_driver", "body": "crank",
         "law": {"type": "ramp", "from": 0, "speed": 30, "ramp_time": 0.1}}],
        "simulation": {"t_end": 0.2, "h": 0.004, "tol_r": 1e-12},
        "output": {"measures": [{"name": "f", "type": "constraint_force",
                                 "joint": closing_last}],
                   "responses": [{"name": "f0", "measure": "f.0", "aggregate": "final"}]}}


@pytest.mark.parametrize("doc, message", [
    (pendulum(velocity=[0, 1], com=[-0.5, 0]),
     r"/bodies/0/velocity: the spatial velocity is the centre of mass's, which needs the angular "
     r"velocity too"),
    (dict(pendulum(), joints=[{"name": "pin", "type": "revolute",
                               "a": {"body": "bob", "at": [-1, 0]}, "b": {"ground": [0, 0.05]}}]),
     r"/joints/0: not assembled at t = 0: a at \[0.0, 0.0\] and b at \[0.0, 0.05\] are 0.05 m "
     r"apart"),
    (pendulum(mas=1), r"/bodies/0/mas: unknown key"),
    (dict(pendulum(), output={"measures": [{"name": "f", "type": "constraint_force",
                                            "joint": "pin"}],
                              "responses": [{"name": "r", "measure": "f.2",
                                             "aggregate": "final"}]}),
     r"/output/responses/0/measure: 'f.2' has no spatial equation"),
    (four_bar("A"), r"/output/responses/0/measure: 'f.0' has no spatial equation of the same sign "
                    r"and frame"),
    (dict(pendulum(), conditions=[{"name": "c", "set": {"/bodies/bob/inertia": 0.2}}]),
     r"/conditions/0/set//bodies/bob/inertia: not carried over"),
    (dict(pendulum(), joints=[{"name": "rail", "type": "prismatic", "a": {"body": "bob"},
                               "direction": [0, 0]}]),
     r"/joints/0/direction: expected a non-zero direction"),
])
def test_what_the_converter_cannot_write_the_same_is_refused_by_its_path(doc, message):
    with pytest.raises(ValueError, match=message):
        to_spatial(doc)


def test_an_inline_joint_to_the_ground_keeps_its_forces_and_they_converge(tmp_path):
    # the loop closed by O4 (to the ground): the inline joint's frame is the ground's
    doc = four_bar("O4")
    doc3, _ = to_spatial(doc)
    assert [j["type"] for j in doc3["joints"][:4]] == ["revolute", "revolute", "revolute", "inline"]
    d = []
    for h in (0.001, 0.0005):
        f = []
        for tag, dd in (("2d", doc), ("3d", doc3)):
            dd = dict(dd, simulation={"t_end": 0.2, "h": h, "tol_r": 1e-12})
            p = tmp_path / f"{tag}.json"
            p.write_text(json.dumps(dd))
            f.append(lsmbs.simulate(lsmbs.load_case(str(p))).responses["f0"])
        d.append(abs(f[1] - f[0]))
        print(f"four-bar O4 force x at h = {h}: 2D {f[0]:.6g}, 3D {f[1]:.6g}")
    assert 1.7 < math.log2(d[0] / d[1]) < 2.3, d


def test_conditions_are_carried_by_name_and_table_files_follow_the_case(tmp_path):
    doc = pendulum()
    doc["joints"].append({"name": "tq", "type": "rotation_driver", "body": "bob",
                          "law": {"type": "table", "file": "law.csv"}})
    doc["conditions"] = [{"name": "fast", "set": {"/joints/1/law": {"type": "table",
                                                                   "file": "law2.csv"},
                                                  "/simulation/h": 0.001}}]
    doc3, _ = to_spatial(doc, src_dir=str(tmp_path / "in"), out_dir=str(tmp_path / "out"))
    c = doc3["conditions"][0]["set"]
    assert set(c) == {"/joints/tq/law", "/simulation/h"}
    assert doc3["joints"][-1]["law"]["file"] == "../in/law.csv"
    assert c["/joints/tq/law"]["file"] == "../in/law2.csv"


def test_the_command_line_refuses_bad_output_paths_without_a_traceback(tmp_path):
    src = tmp_path / "p.json"
    src.write_text(json.dumps(pendulum()))
    script = str(ROOT / "scripts/planar_to_spatial.py")
    for out, phrase in ((tmp_path / "no_such_folder" / "x.json", "does not exist"),
                        (tmp_path, "a folder")):
        p = subprocess.run([sys.executable, script, str(src), "-o", str(out), "--overwrite"],
                           capture_output=True, text=True)
        assert p.returncode == 2 and phrase in p.stderr and "Traceback" not in p.stderr, p.stderr
    bad = tmp_path / "latin1.json"
    bad.write_bytes(b'{"name": "\xe9"}')
    p = subprocess.run([sys.executable, script, str(bad), "-o", str(tmp_path / "o.json")],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert not list(tmp_path.glob("*.tmp"))
