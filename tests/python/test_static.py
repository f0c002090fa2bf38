"""`lsmbs static` and lsmbs.static: static equilibrium. References: the closed-form equilibrium of
a mass hanging on a spring (exact for the linear model), and Euler–Bernoulli/Timoshenko beam
theory for a clamped plate under a tip load."""
import json
import math
import subprocess

import numpy as np
import pytest

import lsmbs
from lsmbs import at, ground, nearest, rectangle

from conftest import CLI, run_cli

M, K, G, L0 = 3.0, 1500.0, 9.81, 0.4


def hanging_mass():
    m = lsmbs.ModelBuilder("hanging", gravity=(0, -G))
    m.rigid_body("block", position=(0, -L0), mass=M)
    m.prismatic("guide", at("block"), (0, 1))
    m.spring_damper("spring", at("block"), ground((0, 0)), stiffness=K, free_length=L0)
    m.measure("block", "position", point=at("block"))
    m.measure("force", "constraint_force", joint="guide")
    m.response("y", "block.y", "final")
    m.simulation(t_end=0.1, h=0.01)
    return m


def test_a_mass_on_a_spring_hangs_at_m_g_over_k():
    r = lsmbs.static(hanging_mass().build())
    assert r.status == "complete"
    assert r.responses["y"] == pytest.approx(-L0 - M * G / K, rel=1e-12)
    assert r.measures["block.x"] == pytest.approx(0, abs=1e-14)


def test_the_command_line_writes_the_same_equilibrium_and_the_vtk_files(tmp_path):
    E, nu, t, h, L, F = 70e9, 0.0, 0.01, 0.02, 0.5, 20.0
    m = lsmbs.ModelBuilder("cantilever")
    m.flexible_body("beam", rectangle((0, -h / 2), (L, h), (100, 4)), E=E, nu=nu, rho=2700,
                    thickness=t)
    m.clamp("root", "beam", "left")
    m.point_force("tip_load", nearest("beam", (L, 0)), (0, -F))
    m.measure("tip", "position", point=nearest("beam", (L, 0)))
    m.response("tip_y", "tip.y", "final")
    m.simulation(t_end=0.01, h=0.01)
    m.save(tmp_path / "cantilever.json")
    S = run_cli("static", tmp_path / "cantilever.json", "-o", tmp_path / "out")
    I = t * h**3 / 12
    G_shear = E / (2 * (1 + nu))
    beam = F * L**3 / (3 * E * I) + F * L / (5 / 6 * G_shear * t * h)  # Timoshenko
    assert S["status"] == "complete"
    assert -S["responses"]["tip_y"] == pytest.approx(beam, rel=2e-2)
    assert S["responses"]["tip_y"] == lsmbs.static(m.build()).responses["tip_y"]
    assert (tmp_path / "out" / "beam.vtu").stat().st_size > 1000
    assert set(S["files"]) == {"summary.json", "history.csv", "beam.vtu", "model.vtm", "final_state.json"}
    rows = (tmp_path / "out" / "history.csv").read_text().splitlines()
    assert len(rows) == 2


def test_a_cantilever_of_triangles_from_the_builder_bends_as_timoshenko():
    """rectangle(..., cells="tri3"): constant-strain triangles on the same nodes, stiffer than the
    quadrilaterals on a coarse mesh and within 2 % of beam theory on a fine one."""
    E, nu, t, h, L, F = 70e9, 0.0, 0.01, 0.02, 0.5, 20.0
    I = t * h**3 / 12
    beam = F * L**3 / (3 * E * I) + F * L / (5 / 6 * E / (2 * (1 + nu)) * t * h)  # Timoshenko

    def tip(cells, nx, ny):
        m = lsmbs.ModelBuilder("cantilever")
        m.flexible_body("beam", rectangle((0, -h / 2), (L, h), (nx, ny), cells=cells), E=E, nu=nu,
                        rho=2700, thickness=t)
        m.clamp("root", "beam", "left")
        m.point_force("tip_load", nearest("beam", (L, 0)), (0, -F))
        m.measure("tip", "position", point=nearest("beam", (L, 0)))
        m.response("tip_y", "tip.y", "final")
        m.simulation(t_end=0.01, h=0.01)
        assert m.document()["bodies"][0]["mesh"].get("cells", "quad4") == cells
        return -lsmbs.static(m.build()).responses["tip_y"]

    assert tip("tri3", 50, 2) < tip("quad4", 50, 2)
    assert tip("tri3", 400, 16) == pytest.approx(beam, rel=2e-2)
    with pytest.raises(lsmbs.Error, match="cells"):
        tip("tri6", 4, 1)


def test_static_refuses_bad_options_and_reports_a_failure(tmp_path):
    b = hanging_mass()
    b.save(tmp_path / "h.json")
    p = subprocess.run([CLI, "static", str(tmp_path / "h.json"), "--max-iter", "0", "-o",
                        str(tmp_path / "o")], capture_output=True, text=True)
    assert p.returncode == 2 and "max-iter" in p.stderr
    # no stiffness: nothing holds the block against gravity
    b = hanging_mass()
    doc = b.document()
    doc["forces"][0]["stiffness"] = 0.0
    (tmp_path / "free.json").write_text(json.dumps(doc))
    p = subprocess.run([CLI, "static", str(tmp_path / "free.json"), "-o", str(tmp_path / "f"),
                        "-q"], capture_output=True, text=True)
    assert p.returncode == 1, p.stderr
    S = json.loads((tmp_path / "f" / "summary.json").read_text())
    assert S["status"] == "partial" and S["failure"] and S["responses"]["y"] is None


def test_a_body_that_nothing_holds_has_no_static_equilibrium(tmp_path):
    """A solid under gravity with no joint: its stiffness is singular up to round-off and Newton
    runs off along the fall, where the round-off floors of the rows grow until they pass. The
    run is refused (exit 1, partial) instead of reporting an equilibrium thousands of km away;
    the same solid clamped at one end hangs at Timoshenko's deflection."""
    import json
    doc = {"name": "free", "dimension": 3, "gravity": [0, 0, -1],
           "bodies": [{"name": "beam", "type": "solid",
                       "mesh": {"type": "box", "origin": [0, -0.5, -0.5], "size": [10, 1, 1],
                                "elements": [8, 1, 1]},
                       "material": {"E": 1e7, "nu": 0, "rho": 1}}],
           "simulation": {"t_end": 0.01, "h": 0.002},
           "output": {"measures": [{"name": "tip", "type": "node_set_position", "body": "beam",
                                    "node_set": "xmax"}]}}
    case = tmp_path / "free.json"
    case.write_text(json.dumps(doc))
    s = run_cli("static", case, "-o", tmp_path / "o1", exit_codes=(1,))
    assert s["status"] != "complete"
    p = subprocess.run([CLI, "static", str(case), "-o", str(tmp_path / "o2")], capture_output=True,
                       text=True)
    assert p.returncode == 1 and "a body or a rigid motion is not held" in p.stderr + p.stdout
    doc["joints"] = [{"name": "clamp", "type": "solid_connection", "solid": "beam",
                      "node_set": "xmin", "body": "ground"}]
    case.write_text(json.dumps(doc))
    run_cli("static", case, "-o", tmp_path / "o3")
    tip = np.genfromtxt(tmp_path / "o3" / "history.csv", delimiter=",", names=True)["tipz"]
    delta = 1e4 / (8 * 1e7 / 12) + 100 / (2 * 5 / 6 * 5e6)  # qL⁴/(8EI) + qL²/(2κGA), q = 1 N/m
    assert np.ravel(tip)[-1] == pytest.approx(-delta, rel=0.02)
