"""The walk-through of docs/getting-started.md, command by command, on its case
(examples/getting_started/flexible_arm.json): each step's result against an independent
reference, so that the document stays true."""
import json

import pytest

from conftest import ROOT, run_cli

CASE = ROOT / "examples" / "getting_started" / "flexible_arm.json"
LIMIT = 1.25e-4  # the case's constraint on the RMS deflection [m]


def test_simulate_gives_the_mass_of_the_drawn_arm(tmp_path):
    S = run_cli("simulate", CASE, "-o", tmp_path / "sim")
    assert S["status"] == "complete"
    # 0.4 × 0.03 × 0.005 m of aluminium less two discs of 6 mm: the level-set band's error only
    exact = 2700 * 0.005 * (0.4 * 0.03 - 2 * 3.141592653589793 * 0.006**2)
    assert S["responses"]["arm_mass"] == pytest.approx(exact, rel=2e-3)


def test_sensitivity_check_agrees_with_central_differences(tmp_path):
    S = run_cli("sensitivity", CASE, "--check", "-o", tmp_path / "sens")
    assert S["gradient_check"]["verdict"] == "pass", S["gradient_check"]


def test_optimize_ends_on_the_bound_found_by_bisection(tmp_path):
    """The optimum: r2 at its upper bound, and the largest r1 whose arm meets the deflection
    limit (the mass falls as r1 grows). Bisection on r1 with simulations alone (no gradient)."""
    S = run_cli("optimize", CASE, "-o", tmp_path / "opt")
    assert S["status"] == "complete" and S["converged"], S["stop_reason"]
    assert S["kkt"]["verdict"] == "satisfied"
    p = S["final"]["design"]
    assert p["r2"] == pytest.approx(0.013, abs=1e-9)

    def rms(r1):
        out = tmp_path / f"r1_{r1:.9f}"
        T = run_cli("simulate", CASE, "--set", f"r1={r1!r}", "--set", "r2=0.013", "-o", out)
        return T["responses"]["rms_deflection"]

    lo, hi = 0.006, 0.013
    assert rms(lo) < LIMIT < rms(hi)
    for _ in range(10):  # to 7e-6 m
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if rms(mid) < LIMIT else (lo, mid)
    assert p["r1"] == pytest.approx(0.5 * (lo + hi), abs=1e-5)
    assert S["final"]["max_violation"] <= 1e-6
