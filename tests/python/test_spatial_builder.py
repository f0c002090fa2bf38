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
