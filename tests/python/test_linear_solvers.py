"""The two sparse LU factorizations behind the integrator and the sensitivity methods (KLU and
UMFPACK, "simulation": {"linear_solver"}). Reference: the same run with the other factorization.
Both are exact direct solvers with threshold pivoting, so responses and gradients agree to
round-off amplified by the Newton tolerance, not to a discretization error; a factorization that
solved the wrong system, transposed the adjoint's, or lost the sensitivity right-hand sides
would differ at the first digit. Then the automatic choice (KLU where the factors fill little,
UMFPACK on 3D solid meshes), what summary.json records, and the error for an unknown solver."""
import json
import subprocess

import numpy as np
import pytest

import lsmbs
from conftest import ROOT, CLI

SOLID_ARM = ROOT / "data" / "spatial" / "solid_arm.json"
PLANAR = ROOT / "data" / "slider_crank" / "slider_crank_1hole_coarse.json"


def run(path, solver, method, t_end=None):
    case = lsmbs.load_case(str(path))
    case.simulation.linear_solver = solver
    if t_end:
        case.simulation.t_end = t_end
    r = lsmbs.sensitivity(case, method=method)
    assert r.status == "complete", r.message
    return r


def relative_difference(a, b):
    """Worst difference over responses (per-step values) and gradients, relative to each
    response's largest value or gradient entry."""
    worst = 0.0
    for k in a.values:
        va, vb = np.asarray(a.values[k]), np.asarray(b.values[k])
        worst = max(worst, float(np.abs(va - vb).max() / max(np.abs(vb).max(), 1e-300)))
        ga, gb = np.asarray(a.gradients[k]), np.asarray(b.gradients[k])
        worst = max(worst, float(np.abs(ga - gb).max() / max(np.abs(gb).max(), 1e-300)))
    return worst


@pytest.mark.parametrize("method", ["direct-analytic", "adjoint"])
def test_umfpack_and_klu_give_the_same_responses_and_gradients_on_a_solid(method):
    klu = run(SOLID_ARM, "klu", method, t_end=0.02)
    umf = run(SOLID_ARM, "umfpack", method, t_end=0.02)
    d = relative_difference(umf, klu)
    print("solid arm, %s: UMFPACK against KLU %.2e" % (method, d))
    assert d < 1e-8


def amg_built():
    try:
        lsmbs.load_case(str(SOLID_ARM)).simulation.linear_solver = "amg"
        return True
    except ValueError:
        return False


@pytest.mark.parametrize("method", ["direct-analytic", "adjoint"])
def test_amg_and_klu_give_the_same_responses_and_gradients_on_a_solid(method):
    # GMRES on the whole iteration matrix, preconditioned by BoomerAMG on the plate's free nodes
    # and KLU on the rest, to a relative residual of 1e-12: the LU's results to the tolerance the
    # two direct solvers agree to
    if not amg_built():
        pytest.skip("this build of lsmbs has no hypre")
    klu = run(SOLID_ARM, "klu", method, t_end=0.02)
    amg = run(SOLID_ARM, "amg", method, t_end=0.02)
    d = relative_difference(amg, klu)
    print("solid arm, %s: AMG-GMRES against KLU %.2e" % (method, d))
    assert amg.summary["primal"]["linear_preconditioner"] == "thin"  # a plate 2 bricks thick
    assert klu.summary["primal"]["linear_preconditioner"] == ""
    assert d < 1e-8


def test_amg_on_a_bulky_block_gives_the_lu_results_with_its_one_v_cycle_preconditioner(tmp_path):
    # a block 4 bricks thick takes the bulky preconditioner (aggressive coarsening, the sweep C, F:
    # one V-cycle), the drilled plate above the thin one: its responses and gradients (a spherical
    # void's radius and the clamp-to-tip response) against KLU's, and bench.json says which ran
    case = block([0.3, 0.15, 0.1], [12, 6, 4], "average", 5)
    case["design"] = {"variables": [{"name": "r", "initial": 0.03, "lower": 0.01, "upper": 0.045}],
                      "geometry": [{"body": "block", "features": [
                          {"name": "void", "type": "sphere", "cx": 0.15, "cy": 0.075, "cz": 0.05,
                           "r": "r"}]}]}
    cf = tmp_path / "bulky.json"
    cf.write_text(json.dumps(case))
    if not amg_built():
        pytest.skip("this build of lsmbs has no hypre")
    b, _ = bench(tmp_path, cf, "bulky_amg", "/simulation/linear_solver=amg")
    assert b["model"]["amg_block"]["preconditioner"] == "bulky", b["model"]
    assert b["model"]["amg_block"]["element_layers"] == 4  # snapped to the integer
    # the box shifted far from the origin: round-off in the positions, the same count
    far = json.loads(cf.read_text())
    far["bodies"][0]["mesh"]["origin"] = [123.4, -56.7, 8.9]
    far["design"]["geometry"][0]["features"][0].update(cx=123.55, cy=-56.625, cz=8.95)
    ff = tmp_path / "bulky_far.json"
    ff.write_text(json.dumps(far))
    b, _ = bench(tmp_path, ff, "bulky_far_amg", "/simulation/linear_solver=amg")
    assert b["model"]["amg_block"]["element_layers"] == 4, b["model"]
    assert b["model"]["amg_block"]["preconditioner"] == "bulky"
    for method in ("direct-analytic", "adjoint"):
        klu = run(cf, "klu", method)
        amg = run(cf, "amg", method)
        d = relative_difference(amg, klu)
        print("bulky block, %s: AMG-GMRES against KLU %.2e" % (method, d))
        assert amg.summary["primal"]["linear_preconditioner"] == "bulky"
        assert d < 1e-8
        assert np.abs(np.asarray(amg.gradients["tip_z"])).max() > 0


def test_umfpack_and_klu_agree_on_a_planar_case():
    klu = run(PLANAR, "klu", "direct-analytic", t_end=0.02)
    umf = run(PLANAR, "umfpack", "direct-analytic", t_end=0.02)
    d = relative_difference(umf, klu)
    print("slider crank (coarse), direct: UMFPACK against KLU %.2e" % d)
    assert d < 1e-8


def block(size, elements, aggregate, steps):
    """An aluminium block of bricks clamped at x = 0, released under its weight for `steps` steps
    of 0.1 ms; the response: the free end's mean z (`aggregate` over the run)."""
    return {"name": "block", "dimension": 3, "gravity": [0, 0, -9.81],
            "bodies": [{"name": "block", "type": "solid",
                        "mesh": {"type": "box", "origin": [0, 0, 0], "size": size,
                                 "elements": elements},
                        "material": {"E": 7e10, "nu": 0.3, "rho": 2700}}],
            "joints": [{"name": "clamp", "type": "solid_connection", "solid": "block",
                        "node_set": "xmin", "body": "ground"}],
            "simulation": {"t_end": steps * 1e-4, "h": 1e-4},
            "output": {"measures": [{"name": "tip", "type": "node_set_position",
                                     "body": "block", "node_set": "xmax"}],
                       "responses": [{"name": "tip_z", "measure": "tip.z",
                                      "aggregate": aggregate}]}}


def bench(tmp_path, case, name, *sets):
    out = tmp_path / name
    args = [CLI, "bench", str(case), "-o", str(out), "-q", "--methods", "none",
            "--repetitions", "1", "--threads", "1"]
    for s in sets:
        args += ["--set", s]
    p = subprocess.run(args, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return json.loads((out / "bench.json").read_text()), json.loads(
        (out / "summary.json").read_text())


def test_the_automatic_choice_and_the_override_are_recorded(tmp_path):
    # a planar case fills little: KLU; a 3D block of 24 x 12 x 6 bricks fills its factors eight
    # times its matrix: UMFPACK (the threshold: SparseLU::auto_fill_threshold)
    b, _ = bench(tmp_path, PLANAR, "planar", "/simulation/t_end=0.002")
    assert b["model"]["linear_solver"] == "klu"
    block_case = tmp_path / "block.json"
    block_case.write_text(json.dumps(block([0.4, 0.2, 0.1], [24, 12, 6], "final", 2)))
    b, s = bench(tmp_path, block_case, "block")
    assert b["model"]["linear_solver"] == "umfpack", b["model"]
    assert b["model"]["lu_nonzeros"] > 5 * b["model"]["nonzeros"]
    # the user's choice wins, and the run records what was asked
    b, s = bench(tmp_path, block_case, "block_klu", "/simulation/linear_solver=klu")
    assert b["model"]["linear_solver"] == "klu"
    assert "/simulation/linear_solver=klu" in json.dumps(s)
    if amg_built():
        b, s = bench(tmp_path, block_case, "block_amg", "/simulation/linear_solver=amg")
        assert b["model"]["linear_solver"] == "amg"


def test_an_unknown_solver_is_refused_with_its_path(tmp_path):
    p = subprocess.run([CLI, "simulate", str(PLANAR), "-o", str(tmp_path / "x"),
                        "--set", "/simulation/linear_solver=pardiso"],
                       capture_output=True, text=True)
    assert p.returncode == 2
    assert "/simulation/linear_solver" in p.stderr
    assert '"auto", "klu", "umfpack"' in p.stderr, p.stderr
    case = lsmbs.load_case(str(PLANAR))
    with pytest.raises(ValueError, match="expected auto, klu, umfpack or amg"):
        case.simulation.linear_solver = "pardiso"


def test_static_equilibrium_takes_the_solver_and_records_it(tmp_path):
    """lsmbs static factorizes with the case's linear_solver too (it ignored the key before):
    the solid arm's equilibrium by UMFPACK against KLU's, and summary.json says which ran."""
    out = {}
    solvers = ("klu", "umfpack", "amg") if amg_built() else ("klu", "umfpack")
    for solver in solvers:
        o = tmp_path / solver
        p = subprocess.run([CLI, "static", str(SOLID_ARM), "-o", str(o), "-q",
                            "--set", "/simulation/linear_solver=" + solver],
                           capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        out[solver] = json.loads((o / "summary.json").read_text())
        assert out[solver]["counts"]["linear_solver"] == solver
    for k, v in out["klu"]["responses"].items():
        for solver in solvers[1:]:
            assert out[solver]["responses"][k] == pytest.approx(v, rel=1e-9, abs=1e-15), k
