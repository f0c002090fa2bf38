"""Spatial models built in Python (lsmbs.SpatialModelBuilder, "dimension": 3).

References: the closed-form loop closure of the spatial slider-crank, the shipped case file of
the same mechanism (the same responses and gradients bit for bit: the builder writes the document
the loader reads), and what the builder refuses."""
import json
import math

import numpy as np
import pytest

import lsmbs

from conftest import ROOT

CASE = ROOT / "data" / "spatial" / "slider_crank_spatial.json"


def slider_crank():
    """data/spatial/slider_crank_spatial.json, rebuilt call by call from its own numbers."""
    doc = json.loads(CASE.read_text())
    m = lsmbs.SpatialModelBuilder("slider_crank_spatial", gravity=doc["gravity"])
    for b in doc["bodies"]:
        m.rigid_body(b["name"], position=b["position"], mass=b["mass"], inertia=b["inertia"],
                     orientation=b.get("orientation"))
    j = {e["name"]: e for e in doc["joints"]}
    m.revolute("bearing", "ground", "crank", j["bearing"]["at"], j["bearing"]["axis"])
    m.spherical("pin", "crank", "rod", j["pin"]["at"])
    m.universal("wrist", "slider", "rod", j["wrist"]["at"], j["wrist"]["axis"], j["wrist"]["axis_b"])
    m.prismatic("slide", "ground", "slider", j["slide"]["at"], j["slide"]["axis"])
    m.rotation_driver("motor", "bearing", lsmbs.ramp(100, 0.05))
    s = doc["forces"][0]
    m.spring_damper("spring", "ground", s["a_at"], "slider", s["b_at"], s["stiffness"],
                    damping=s["damping"])
    for e in doc["output"]["measures"]:
        m.measure(e["name"], e["type"], **{k: v for k, v in e.items() if k not in ("name", "type")})
    for r in doc["output"]["responses"]:
        m.response(r["name"], r["measure"], r["aggregate"])
    for v in doc["design"]["variables"]:
        m.variable(v["name"], v["initial"], v["lower"], v["upper"])
    for p in doc["design"]["parameters"]:
        m.bind_parameter(p["parameter"], p["variable"])
    m.simulation(**doc["simulation"])
    return m


def test_the_built_slider_crank_closes_its_loop_and_equals_the_shipped_case():
    built = slider_crank().build()
    r = lsmbs.simulate(built)
    th, y = np.array(r.column("crank_angle")), np.array(r.column("slider.y"))
    closed = 0.1 * np.cos(th) + np.sqrt(0.3**2 - 0.2**2 - (0.1 * np.sin(th)) ** 2)
    assert np.max(np.abs(y - closed)) < 1e-10
    assert th[-1] > 4 * math.pi
    s_built = lsmbs.sensitivity(built, method="direct-analytic")
    s_file = lsmbs.sensitivity(lsmbs.load_case(str(CASE)), method="direct-analytic")
    for name, value in s_file.values.items():
        assert s_built.values[name] == value
        assert list(s_built.gradients[name]) == list(s_file.gradients[name])


def test_the_spatial_builder_refuses_what_spatial_cases_do_not_have():
    m = lsmbs.SpatialModelBuilder("m")
    m.rigid_body("b", mass=1, inertia=(1, 1, 1))
    with pytest.raises(NotImplementedError, match="planar kind"):
        m.clamp("c", "b", "left")
    with pytest.raises(NotImplementedError, match="a flexible component of a spatial mechanism "
                                                  "is a solid_body"):
        m.flexible_body("plate", None, E=1, nu=0.3, rho=1, thickness=1)
    with pytest.raises(ValueError, match=r"elements: expected three positive integers"):
        m.solid_body("s", size=(1, 1, 1), elements=(2, 0, 1), E=1, nu=0.3, rho=1)
    with pytest.raises(TypeError, match="nu"):
        m.solid_body("s", size=(1, 1, 1), elements=(2, 1, 1), E=1, rho=1)  # ν has no default
    with pytest.raises(TypeError, match="expected a triple"):
        m.spherical("s", "ground", "b", (0, 0))
    with pytest.raises(TypeError, match="has no key 'point'"):
        m.measure("p", "position", point=(0, 0, 0))
    m.universal("u", "ground", "b", (0, 0, 0), (1, 0, 0), (1, 0, 0))  # axes not perpendicular
    m.simulation(t_end=0.1, h=0.01)
    with pytest.raises(lsmbs.Error, match=r"universal\('u'\): axis_b: expected a direction "
                                          r"perpendicular"):
        m.build()


SOLID = ROOT / "data" / "spatial" / "solid_cantilever.json"


def test_a_solid_body_built_in_python_equals_the_shipped_case():
    """data/spatial/solid_cantilever.json call by call: the same responses and gradients bit for
    bit (the builder writes the document the loader reads), and the clamped tip at rest at t = 0."""
    doc = json.loads(SOLID.read_text())
    b = doc["bodies"][0]
    m = lsmbs.SpatialModelBuilder("solid_cantilever", gravity=doc["gravity"])
    m.solid_body("beam", origin=b["mesh"]["origin"], size=b["mesh"]["size"],
                 elements=np.array(b["mesh"]["elements"]), E=1e7, nu=0, rho=1)  # NumPy counts
    m.solid_connection("clamp", "beam", "xmin", "ground")
    m.measure("tip", "node_set_position", body="beam", node_set="xmax")
    for r in doc["output"]["responses"]:
        m.response(r["name"], r["measure"], r["aggregate"])
    for v in doc["design"]["variables"]:
        m.variable(v["name"], v["initial"], v["lower"], v["upper"])
    for p in doc["design"]["parameters"]:
        m.bind_parameter(p["parameter"], p["variable"])
    m.simulation(**doc["simulation"])
    built = m.build()
    r = lsmbs.simulate(built)
    z = np.array(r.column("tip.z"))
    assert z[0] == 0.0 and z.min() < -2.5e-3  # at rest, then swinging to about twice 1.5e-3 m
    s_built = lsmbs.sensitivity(built, method="direct-analytic")
    s_file = lsmbs.sensitivity(lsmbs.load_case(str(SOLID)), method="direct-analytic")
    for name, value in s_file.values.items():
        assert s_built.values[name] == value
        assert list(s_built.gradients[name]) == list(s_file.gradients[name])


ARM = ROOT / "data" / "spatial" / "solid_arm.json"


def test_a_designed_solid_built_in_python_equals_the_shipped_case():
    """data/spatial/solid_arm.json call by call, its 3D level-set design through lsmbs.pocket and
    lsmbs.through_hole with planar profiles: the same document as the file's (what the loader
    reads), so the same responses and gradients; a profile that is not planar is refused."""
    doc = json.loads(ARM.read_text())
    m = lsmbs.SpatialModelBuilder("solid_arm", gravity=doc["gravity"],
                                  description=doc["description"])
    m.rigid_body("hub", position=(0, 0, 0), mass=0.5, inertia=(1e-3, 1e-3, 1e-3))
    m.solid_body("plate", origin=(0, -0.005, -0.04), size=(0.4, 0.01, 0.08), elements=(20, 2, 4),
                 E=7e10, nu=0.3, rho=2700)
    m.rigid_body("payload", position=(0.41, 0, 0), mass=0.5, inertia=(2e-4, 2e-4, 2e-4))
    m.revolute("shoulder", "ground", "hub", at=(0, 0, 0), axis=(0, 0, 1))
    m.rotation_driver("motor", joint="shoulder", law=lsmbs.ramp(10, 0.02))
    m.solid_connection("root", "plate", "xmin", "hub")
    m.solid_connection("tip", "plate", "xmax", "payload")
    m.simulation(t_end=0.04, h=0.001)
    m.measure("tip", "node_set_position", body="plate", node_set="xmax")
    m.measure("mass", "mass", body="plate")
    m.measure("stress", "stress", body="plate", reference=1e7)
    for r in doc["output"]["responses"]:
        m.response(r["name"], r["measure"], r["aggregate"])
    r1 = m.variable("r1", 0.02, 0.005, 0.032)
    r2 = m.variable("r2", 0.016, 0.005, 0.032)
    depth = m.variable("depth", 0.004, 0.001, 0.009)
    m.features("plate", [
        lsmbs.through_hole("hole1", "ymax", lsmbs.circle("p", 0.1, 0, r1)),
        lsmbs.through_hole("hole2", "ymax", lsmbs.circle("p", 0.2, 0, r2)),
        lsmbs.pocket("pocket", "ymax", lsmbs.super_ellipse("p", 0.31, 0, 0.05, 0.025, xi=4, eta=4),
                     depth=depth)], subgrid=16)
    s_built = lsmbs.sensitivity(m.build(), method="direct-analytic")
    s_file = lsmbs.sensitivity(lsmbs.load_case(str(ARM)), method="direct-analytic")
    for name, value in s_file.values.items():
        assert s_built.values[name] == value
        assert list(s_built.gradients[name]) == list(s_file.gradients[name])
    # the mass: the plate less the holes and the pocket (within the band's bias, 2e-3)
    area = 4 * 0.05 * 0.025 * math.gamma(1.25) ** 2 / math.gamma(1.5)
    closed = 2700 * (0.4 * 0.01 * 0.08 - math.pi * (0.02 ** 2 + 0.016 ** 2) * 0.01 - area * 0.004)
    assert abs(s_built.values["plate_mass"] / closed - 1) < 2e-3
    with pytest.raises(ValueError, match="profile: expected a planar circle"):
        lsmbs.pocket("bad", "ymax", lsmbs.sphere("s", 0, 0, 0, 0.01), depth=0.001)


def test_length_scale_constraints_on_a_solid_design(tmp_path):
    """Length-scale constraints on data/spatial/solid_arm.json (`lsmbs geometry`, min_size 8 mm):
    hole1 (r1 = 20 mm, through the 10 mm thickness of the 80 mm tall plate) has the edge ligament
    40 − 20 = 20 mm (the faces it passes through are not edges), the pocket (4 mm deep) its floor,
    6 mm, and each is reported with its 3D position; no_cut is refused naming its key (exit 2, no
    file written), and so is a bound longer than the body (a length in mm given as m)."""
    import subprocess
    from conftest import CLI
    doc = json.loads(ARM.read_text())
    doc["optimization"] = {"objective": "plate_mass", "length_scale": {"min_size": 0.008}}
    case = tmp_path / "arm_ls.json"
    case.write_text(json.dumps(doc))
    p = subprocess.run([CLI, "geometry", str(case), "-o", str(tmp_path / "g"), "-q"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    s = json.loads((tmp_path / "g" / "summary.json").read_text())
    c = {x["name"]: x for x in s["length_scale"]["plate"]["constraints"]}
    err = 0.05 * 0.008
    assert 0.020 - err <= c["edge.hole1"]["value"] <= 0.020 + 1e-4
    assert 0.006 - err <= c["edge.pocket"]["value"] <= 0.006 + 1e-9
    assert len(c["edge.pocket"]["at"]) == 3 and c["edge.pocket"]["at"][1] == pytest.approx(-0.005)
    assert c["member.hole1"]["value"] == pytest.approx(0.04)
    for bad, key in (({"no_cut": 0.004}, "/optimization/length_scale/no_cut"),
                     ({"min_size": 0.5}, "/optimization/length_scale/min_ligament")):
        doc["optimization"]["length_scale"] = bad
        case.write_text(json.dumps(doc))
        out = tmp_path / ("bad_" + key.rsplit("/", 1)[1])
        p = subprocess.run([CLI, "geometry", str(case), "-o", str(out), "-q"],
                           capture_output=True, text=True)
        assert p.returncode == 2, p.stderr
        assert key in p.stderr, p.stderr
        assert not out.exists() or not any(out.iterdir()), "nothing written for a bad input"


def test_optimizing_a_solid_design_judges_it(tmp_path):
    """`lsmbs optimize` on data/spatial/solid_arm.json (mass under a stress bound, two
    evaluations) judges the solid design: summary.json's judgement has the plate's resolution
    (one piece; every part with its width, 3D position and the threshold across it) and the
    load-path check of both responses; the KKT line names every measure it judges by,
    complementarity included."""
    import subprocess
    from conftest import CLI
    doc = json.loads(ARM.read_text())
    doc["optimization"] = {"objective": "plate_mass",
                           "constraints": [{"response": "peak_stress", "upper": 6e7}],
                           "optimizer": "mma", "stop": {"max_evaluations": 2}}
    case = tmp_path / "arm.json"
    case.write_text(json.dumps(doc))
    p = subprocess.run([CLI, "optimize", str(case), "-o", str(tmp_path / "out"), "--no-check"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    j = s["judgement"]
    assert j is not None and j["verdict"] in ("sound", "unresolved"), j
    (r,) = j["resolution"]
    assert r["body"] == "plate" and len(r["pieces"]) == 1
    assert all(len(q["at"]) == 3 for q in r["parts"]), r["parts"]
    assert {x["response"] for x in j["load_path"]["responses"]} == {"plate_mass", "peak_stress"}
    assert not any("not judged" in w for w in s["warnings"]), s["warnings"]
    assert "complementarity" in p.stdout, p.stdout
