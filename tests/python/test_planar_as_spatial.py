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
