"""Models built in Python (lsmbs.ModelBuilder), the gradient check and output folders from Python.

References: the closed-form solution of a mass on a spring, central differences of plain
simulations, and the command line run on the saved case file (bit for bit)."""
import json
import math
import warnings

import numpy as np
import pytest

import lsmbs
from lsmbs import at, ground, rectangle

from conftest import ROOT, SPRING, run_cli

M, K0, A, L0 = 2.0, 200.0, 0.01, 0.5  # mass [kg], stiffness [N/m], amplitude [m], free length [m]
T_END, H = 1.0, 1e-3


def oscillator(k=K0, h=H, design=True):
    """A block on a frictionless slide, held by a spring to the ground, released at x = L0 + A
    from rest: x(t) = L0 + A cos(ω t), ω = sqrt(k / m)."""
    m = lsmbs.ModelBuilder("oscillator")
    m.rigid_body("block", position=(L0 + A, 0), mass=M)
    m.prismatic("slide", at("block"), (1, 0))
    m.spring_damper("spring", at("block"), ground((0, 0)), stiffness=k, free_length=L0)
    m.measure("block", "position", point=at("block"))
    m.response("x_end", "block.x", "final")
    m.response("x_mean", "block.x", "average")
    m.simulation(t_end=T_END, h=h, rho_inf=0.9)
    if design:
        v = m.variable("k", initial=k, lower=50, upper=400)
        m.bind_parameter("spring.stiffness", v)
    return m


def x_exact(k, t):
    return L0 + A * math.cos(math.sqrt(k / M) * t)


def test_built_oscillator_follows_the_closed_form():
    r = lsmbs.simulate(oscillator().build())
    x = r.column("block.x")
    exact = np.array([x_exact(K0, t) for t in r.times])
    # generalized-α is second order: the phase error after 1.6 periods is (ω h)² ω T / 24 ≈ 4e-5 rad
    assert np.max(np.abs(x - exact)) < 2e-3 * A
    assert r.times[-1] == pytest.approx(T_END, abs=1e-12)


def test_gradient_of_a_built_model_agrees_with_the_closed_form_and_central_differences():
    case = oscillator().build()
    s = lsmbs.sensitivity(case, method="direct-analytic")
    g = s.gradients["x_end"][0]
    w = math.sqrt(K0 / M)
    closed = -A * math.sin(w * T_END) * T_END / (2 * math.sqrt(K0 * M))  # d x(T) / dk
    assert g == pytest.approx(closed, rel=5e-3)
    # central differences of two plain simulations of rebuilt models (no sensitivity code)
    d = 1e-3
    fd = (lsmbs.simulate(oscillator(K0 + d, design=False).build()).responses["x_end"]
          - lsmbs.simulate(oscillator(K0 - d, design=False).build()).responses["x_end"]) / (2 * d)
    assert g == pytest.approx(fd, rel=1e-6)


def test_a_saved_model_runs_on_the_command_line_to_the_same_numbers_bit_for_bit(tmp_path):
    b = oscillator()
    case = b.build()
    b.save(tmp_path / "osc.json")
    s = lsmbs.sensitivity(case, method="direct-analytic")
    S = run_cli("sensitivity", tmp_path / "osc.json", "--method", "direct-analytic",
                "-o", tmp_path / "out")
    assert S["case_sha256"] == case.sha256  # build() hashes the text save() writes
    for name, value in s.values.items():
        assert S["responses"][name] == value  # exact
        assert [S["gradients"][name][v] for v in s.variables] == list(s.gradients[name])


def test_a_flexible_model_with_features_builds_and_matches_the_same_case_file(tmp_path):
    """A clamped plate with one design hole built in Python equals the case file written by hand
    from docs/case-format.md (same responses and gradients bit for bit)."""
    m = lsmbs.ModelBuilder("plate")
    m.flexible_body("plate", rectangle((0, -0.025), (0.3, 0.05), (24, 4)),
                    E=70e9, nu=0.3, rho=2700, thickness=0.002)
    m.clamp("root", "plate", "left")
    m.point_force("load", lsmbs.nearest("plate", (0.3, 0.0)), (0, -50))
    r = m.variable("r", initial=0.01, lower=0.002, upper=0.02)
    m.features("plate", [lsmbs.circle("hole", 0.15, 0.0, r)])
    m.measure("tip", "position", point=lsmbs.nearest("plate", (0.3, 0.0)))
    m.measure("mass", "mass", body="plate")
    m.response("tip_y", "tip.y", "final")
    m.response("plate_mass", "mass", "final")
    m.simulation(t_end=0.02, h=0.002)
    by_hand = {
        "name": "plate", "gravity": [0, 0],
        "bodies": [{"name": "plate", "type": "flexible",
                    "mesh": {"type": "rectangle", "origin": [0, -0.025], "size": [0.3, 0.05],
                             "elements": [24, 4]},
                    "material": {"E": 70e9, "nu": 0.3, "rho": 2700}, "thickness": 0.002}],
        "joints": [{"name": "root", "type": "clamp", "flexible": "plate", "node_set": "left"}],
        "forces": [{"name": "load", "type": "point_force",
                    "point": {"body": "plate", "nearest": [0.3, 0.0]}, "force": [0, -50]}],
        "design": {"variables": [{"name": "r", "initial": 0.01, "lower": 0.002, "upper": 0.02}],
                   "geometry": [{"body": "plate", "features": [
                       {"name": "hole", "type": "circle", "cx": 0.15, "cy": 0, "r": "r"}]}]},
        "simulation": {"t_end": 0.02, "h": 0.002},
        "output": {"measures": [
            {"name": "tip", "type": "position", "point": {"body": "plate", "nearest": [0.3, 0.0]}},
            {"name": "mass", "type": "mass", "body": "plate"}],
            "responses": [{"name": "tip_y", "measure": "tip.y", "aggregate": "final"},
                          {"name": "plate_mass", "measure": "mass", "aggregate": "final"}]}}
    (tmp_path / "by_hand.json").write_text(json.dumps(by_hand))
    built = lsmbs.sensitivity(m.build())
    hand = lsmbs.sensitivity(lsmbs.load_case(tmp_path / "by_hand.json"))
    for name in ("tip_y", "plate_mass"):
        assert built.values[name] == hand.values[name]
        assert np.array_equal(built.gradients[name], hand.gradients[name])
    # the hole's area: the mass falls by ρ t π r² (to the mapping's resolution)
    g = lsmbs.geometry(m.build())["plate"]
    assert g["mass"] == pytest.approx(2700 * 0.002 * (0.3 * 0.05 - math.pi * 0.01**2), rel=2e-3)


def test_builder_errors_name_the_call():
    b = oscillator()
    b.rigid_body("loose", mass=-1.0)
    with pytest.raises(lsmbs.Error) as e:
        b.build()
    assert e.value.json_path == "/bodies/1/mass"
    assert "rigid_body('loose'): mass: expected a non-negative number" in str(e.value)

    b = oscillator()
    b.revolute("pin", at("nobody"))
    with pytest.raises(lsmbs.Error) as e:
        b.build()
    assert "revolute('pin')" in str(e.value) and "nobody" in str(e.value)

    b = oscillator()
    with pytest.raises(lsmbs.Error, match="taken"):
        b.rigid_body("spring", mass=1)  # a force has that name
    with pytest.raises(TypeError, match="expected a point"):
        b.revolute("pin", (0, 0))
    with pytest.raises(TypeError, match="expected a number"):
        b.rigid_body("x", mass="heavy")
    with pytest.raises(TypeError, match=r"expected a pair"):
        b.rigid_body("y", position=(1, 2, 3))
    b2 = lsmbs.ModelBuilder("no_sim")
    b2.rigid_body("a", mass=1)
    with pytest.raises(lsmbs.Error, match="simulation"):
        b2.build()


def test_built_case_is_independent_of_later_builder_changes():
    b = oscillator()
    first = b.build()
    b.spring_damper("stiffer", at("block"), ground((1, 0)), stiffness=1e3)
    assert lsmbs.simulate(first).responses["x_end"] == pytest.approx(x_exact(K0, T_END), abs=2e-3 * A)


def test_gradient_check_from_python():
    case = lsmbs.load_case(SPRING)
    s = lsmbs.sensitivity(case, method="direct-analytic", check=True)
    gc = s.gradient_check
    assert gc is not None and gc["verdict"] == "pass"
    assert gc["worst"] < 1e-3 and gc["simulations"] == 2
    assert lsmbs.sensitivity(case).gradient_check is None
    with pytest.raises(ValueError, match="check_delta"):
        lsmbs.sensitivity(case, check=True, check_delta=2.0)
    # the options are named by the keywords, also inside the message (not the library's "warn")
    with pytest.raises(ValueError, match=r"^check_fail: .* >= check_warn \(0\.01\), got 0\.001$"):
        lsmbs.sensitivity(case, check=True, check_warn=1e-2, check_fail=1e-3)
    with pytest.raises(ValueError, match=r"^adjoint_memory: expected a non-negative number"):
        lsmbs.sensitivity(case, method="adjoint", adjoint_memory=float("inf"))


def test_optimize_checks_the_initial_gradient_and_refuses_above_check_fail(tmp_path):
    b = oscillator()
    b.optimization("x_mean", stop={"max_evaluations": 3})
    case = b.build()
    # a threshold no gradient meets: the refusal, with the check's record attached
    with pytest.raises(lsmbs.GradientCheckFailed) as e:
        lsmbs.optimize(case, check_warn=1e-300, check_fail=1e-300)
    assert "gradient check at the initial design failed" in str(e.value)
    assert e.value.gradient_check["verdict"] == "fail"
    assert isinstance(e.value, lsmbs.NumericalFailure)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the default thresholds: no warning on this exact gradient
        r = lsmbs.optimize(case, out_dir=str(tmp_path / "opt"))
    assert r["gradient_check"]["verdict"] == "pass"
    S = json.loads((tmp_path / "opt" / "summary.json").read_text())
    assert S["status"] == r["status"] and S["final"]["objective"] == r["final"]["objective"]
    assert S["case_sha256"] == case.sha256 and S["gradient_check"]["verdict"] == "pass"
    assert lsmbs.optimize(case, check=False)["gradient_check"] is None


def test_an_output_folder_with_an_earlier_run_is_refused_unless_overwrite(tmp_path):
    case = oscillator().build()
    out = tmp_path / "run"
    lsmbs.simulate(case, out_dir=str(out))
    with pytest.raises(lsmbs.Error, match=r"earlier run.*overwrite=True"):
        lsmbs.simulate(case, out_dir=str(out))
    lsmbs.simulate(case, out_dir=str(out), overwrite=True)
    assert json.loads((out / "summary.json").read_text())["status"] == "complete"
    # bad input found after the claim (verify loads its case itself): the earlier run comes back
    before = sorted(p.name for p in out.iterdir())
    summary = (out / "summary.json").read_bytes()
    with pytest.raises(lsmbs.Error):
        lsmbs.verify(str(tmp_path / "no_such_case.json"), out_dir=str(out), overwrite=True)
    assert sorted(p.name for p in out.iterdir()) == before
    assert (out / "summary.json").read_bytes() == summary
    (tmp_path / "file").write_text("x")
    with pytest.raises(lsmbs.Error, match="out_dir .*not a folder"):
        lsmbs.simulate(case, out_dir=str(tmp_path / "file"))


def test_the_readme_python_section_runs_and_plots_an_exact_gradient(tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## Python"):]
    code = section[section.index("```python") + 9:section.index("```\n", section.index("```python") + 9)]
    assert len(code.strip().splitlines()) <= 10
    monkeypatch.chdir(tmp_path)
    scope = {}
    exec(compile(code, "README.md", "exec"), scope)
    r = scope["r"]
    assert r["direct-analytic"].gradients["x_end"][0] == pytest.approx(
        r["fd-central"].gradients["x_end"][0], rel=1e-5)
    assert (tmp_path / "gradient.png").stat().st_size > 1000


def test_the_builder_example_of_docs_python_md_builds_a_flexible_arm_with_a_checked_gradient():
    text = (ROOT / "docs" / "python.md").read_text()
    start = text.index("```python", text.index("## Models built in Python")) + 9
    scope = {}
    exec(compile(text[start:text.index("```", start)], "docs/python.md", "exec"), scope)
    s = lsmbs.sensitivity(scope["case"], check=True)
    assert s.gradient_check["verdict"] == "pass", s.gradient_check


def test_parameters_bound_to_design_variables_are_range_checked_over_the_bounds():
    b = oscillator(design=False)
    v = b.variable("m", initial=1.0, lower=0.5, upper=2.0)
    b.bind_parameter("block.mass", v, offset=-1.0)  # -0.5 kg at the lower bound
    with pytest.raises(lsmbs.Error, match=r"bind_parameter\('block.mass'\).*-0.5 at m = 0.5"):
        b.build()


def test_per_step_responses_of_a_simulation_are_arrays_and_a_failed_run_has_none():
    b = oscillator()
    b.response("x_steps", "block.x", "per_step", window=(0.5, 0.6))
    case = b.build()
    r = lsmbs.simulate(case)
    s = lsmbs.sensitivity(case)
    assert np.array_equal(r.responses["x_steps"], s.values["x_steps"])
    assert len(r.responses["x_steps"]) == 101
    assert r.summary["responses"]["x_steps"] == list(s.values["x_steps"])
    # a pendulum released horizontally, one Newton iteration per step allowed and no step
    # halving: the first step cannot converge, the run fails
    p = lsmbs.ModelBuilder("pendulum", gravity=(0, -9.81))
    p.rigid_body("bob", position=(1, 0), mass=1, inertia=0.1)
    p.revolute("pin", at("bob", (-1, 0)))
    p.measure("bob", "position", point=at("bob"))
    p.response("lowest_y", "bob.y", "min")
    p.response("y_steps", "bob.y", "per_step")
    p.simulation(t_end=1, h=0.05, max_iter=1, max_halvings=0)
    f = lsmbs.simulate(p.build())
    assert f.status != "complete"
    assert math.isnan(f.responses["lowest_y"]) and np.all(np.isnan(f.responses["y_steps"]))


def test_resume_from_python_refuses_a_case_changed_since_the_checkpoint(tmp_path):
    b = oscillator()
    b.optimization("x_mean", stop={"max_evaluations": 2})
    case = b.build()
    out = str(tmp_path / "opt")
    lsmbs.optimize(case, out_dir=out, check=False)
    case.parameters["block.mass"] = 3.0
    with pytest.raises(lsmbs.Error, match="changed since the checkpoint"):
        lsmbs.optimize(case, out_dir=out, resume=True)
    case.parameters["block.mass"] = M
    case.simulation.h = 2e-3
    with pytest.raises(lsmbs.Error, match="changed since the checkpoint"):
        lsmbs.optimize(case, out_dir=out, resume=True)
    case.simulation.h = H
    assert lsmbs.optimize(case, out_dir=out, resume=True)["status"] == "complete"


def test_builder_edge_inputs():
    b = oscillator()
    with pytest.raises(ValueError, match="finite"):
        b.rigid_body("n", mass=float("nan"))
    with pytest.raises(TypeError):
        b.variable(3, 1, 0, 2)
    assert "design" in b.document()  # the oscillator's own variable is still there, alone
    assert [v["name"] for v in b.document()["design"]["variables"]] == ["k"]
    with pytest.raises(TypeError, match="pair"):
        b.rigid_body("d", position={"x": 1, "y": 2})
    with pytest.raises(TypeError, match="bind_parameter"):
        b.torque("tq", "block", lsmbs.Variable("k"))
    with pytest.raises(TypeError):
        b.bind_parameter("spring.damping", "k", scale=True)
    v = lsmbs.Variable("r")
    assert (1 - v)._binding() == {"variable": "r", "scale": -1.0, "offset": 1.0}
    assert (v / 2)._binding() == {"variable": "r", "scale": 0.5, "offset": 0.0}


def test_save_elsewhere_keeps_relative_mesh_files(tmp_path, monkeypatch):
    mesh_dir = ROOT / "data" / "slider_crank"
    monkeypatch.chdir(mesh_dir)
    m = lsmbs.ModelBuilder("rod")
    m.flexible_body("rod", lsmbs.gmsh("rod_coarse.msh", scale=1e-3), E=210e9, nu=0.3, rho=7800,
                    thickness=0.01)
    m.measure("mass", "mass", body="rod")
    m.response("rod_mass", "mass", "final")
    m.clamp("fix", "rod", "bore_small")
    m.simulation(t_end=1e-3, h=1e-3)
    built = lsmbs.simulate(m.build()).responses["rod_mass"]
    (tmp_path / "elsewhere").mkdir()
    m.save(tmp_path / "elsewhere" / "rod.json")
    saved = lsmbs.simulate(lsmbs.load_case(tmp_path / "elsewhere" / "rod.json")).responses["rod_mass"]
    assert saved == built


def test_the_forward_semi_analytical_method_says_it_is_not_exact():
    case = oscillator().build()
    assert any("not exact" in w for w in lsmbs.sensitivity(case, method="semi-analytical").warnings)
    assert lsmbs.sensitivity(case).warnings == []


def test_a_bspline_hole_built_in_python_has_the_curves_area_and_its_exact_derivative():
    """A free-form hole (lsmbs.bspline, 8 control points x_i = c + s·R_i, one variable s that
    scales the curve about c): the void area against s² A₁ with A₁ the curve's exact area at
    s = 1 (export.bspline_area, checked against OpenCASCADE in test_export), and ∂m/∂s against
    −2 ρ t s A₁, to the mapping's resolution."""
    from lsmbs import export
    m = lsmbs.ModelBuilder("plate")
    m.flexible_body("plate", rectangle((0, -0.025), (0.3, 0.05), (60, 10)),
                    E=70e9, nu=0.3, rho=2700, thickness=0.002)
    m.clamp("root", "plate", "left")
    s = m.variable("s", initial=1.0, lower=0.5, upper=1.2)
    R = [(0.02 * (1 + 0.25 * math.cos(2 * t)) * math.cos(t), 0.012 * math.sin(t))
         for t in (2 * math.pi * k / 8 for k in range(8))]
    m.features("plate", [lsmbs.bspline("free", control_points=[[s * rx + 0.15, s * ry]
                                                               for rx, ry in R])])
    m.measure("mass", "mass", body="plate")
    m.response("plate_mass", "mass", "final")
    m.simulation(t_end=0.002, h=0.001)
    A1 = export.bspline_area(R)
    rho_t = 2700 * 0.002
    g = lsmbs.geometry(m.build())["plate"]
    void = (rho_t * 0.3 * 0.05 - g["mass"]) / (rho_t * (1 - 1e-3))  # μ_min = 1e-3 in the hole
    assert void == pytest.approx(A1, rel=3e-3)  # measured +0.12 % on 5 mm elements
    r = lsmbs.sensitivity(m.build())
    assert r.gradients["plate_mass"][0] == pytest.approx(-2 * rho_t * A1, rel=3e-3)  # −0.11 %
