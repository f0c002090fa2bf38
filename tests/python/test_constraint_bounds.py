"""Optimization constraints with lower bounds, both bounds, `equals` and a zero bound with a
reference scale. Reference: closed forms. A block of mass m on a frictionless slide, pushed by a
constant force F from x0 at rest: x(T) = x0 + F T² / (2 m), kinetic energy (F T)² / (2 m) (the
generalized-α solution of a constant acceleration is exact). The design variable is m."""
import math

import pytest

import lsmbs
from lsmbs import at

F, T, X0 = 2.0, 0.5, -0.5


def pushed_block(objective, constraints, m0=1.0):
    b = lsmbs.ModelBuilder("pushed_block")
    b.rigid_body("block", position=(X0, 0), mass=1.0)
    b.prismatic("slide", at("block"), (1, 0))
    b.point_force("push", at("block"), (F, 0))
    b.measure("block", "position", point=at("block"))
    b.measure("energy", "kinetic_energy")
    b.response("x_end", "block.x", "final")
    b.response("energy_end", "energy", "final")
    b.simulation(t_end=T, h=T / 50)
    m = b.variable("m", initial=m0, lower=0.05, upper=10.0)
    b.bind_parameter("block.mass", m)
    b.optimization(objective, constraints, stop={"max_evaluations": 60,
                                                 "relative_objective_change": 1e-6})
    return b.build()


def optimum(case):
    r = lsmbs.optimize(case, check=False)
    assert r["status"] == "complete", r["report"]
    # the closed-form optimum is a KKT point: the report must say so where the run reached it
    assert r["kkt"]["verdict"] == "satisfied", r["kkt"]
    assert not any("KKT" in w for w in r["warnings"]), r["warnings"]
    return r["p"][0], r


def test_closed_form_of_the_model():
    case = pushed_block("x_end", [{"response": "energy_end", "lower": 1.0}])
    s = lsmbs.simulate(case, design=[0.25])
    assert s.responses["x_end"] == pytest.approx(X0 + F * T**2 / (2 * 0.25), rel=1e-12)
    assert s.responses["energy_end"] == pytest.approx((F * T) ** 2 / (2 * 0.25), rel=1e-12)


def test_a_lower_bound_is_reached_where_the_closed_form_puts_it():
    # minimize x(T) (m up) subject to E(T) >= 0.4 J: m* = (F T)² / (2 · 0.4)
    m, r = optimum(pushed_block("x_end", [{"response": "energy_end", "lower": 0.4}]))
    assert m == pytest.approx((F * T) ** 2 / 0.8, rel=3e-3)
    e = r["final"]
    assert e["constraints"][0] == pytest.approx(-(F * T) ** 2 / (2 * m), rel=1e-12)  # g = -E
    assert e["upper"][0] == -0.4 and e["scale"][0] == 0.4


def test_a_zero_lower_bound_with_a_reference_scale():
    # minimize x(T) subject to x(T) >= 0 (scale 0.1 m): m* = F T² / (2 · 0.5); from a feasible
    # start (NLopt's MMA, started at the infeasible m = 1, stops at its first feasible point)
    m, r = optimum(pushed_block("x_end", [{"response": "x_end", "lower": 0, "scale": 0.1}], 0.2))
    assert m == pytest.approx(F * T**2 / (2 * -X0), rel=3e-3)
    assert r["final"]["scale"][0] == 0.1


def test_equals_holds_the_response_at_the_value_from_either_side():
    # E(T) = 0.25 J whatever the objective's direction: m* = (F T)² / 0.5
    for objective in ("x_end", "energy_end"):
        m, _ = optimum(pushed_block(objective, [{"response": "energy_end", "equals": 0.25}]))
        assert m == pytest.approx((F * T) ** 2 / 0.5, rel=3e-3), objective


@pytest.mark.parametrize("entry,words", [
    ({"response": "x_end"}, "expected \"upper\", \"lower\", both, or \"equals\""),
    ({"response": "x_end", "upper": 0}, "a zero bound needs \"scale\""),
    ({"response": "x_end", "lower": 1, "upper": 0.5}, "expected lower <= upper"),
    ({"response": "x_end", "equals": 1, "upper": 2}, "\"equals\" alone"),
    ({"response": "x_end", "upper": 1, "scale": -1}, "scale"),
])
def test_bad_constraint_entries_name_their_key(entry, words):
    with pytest.raises(lsmbs.Error) as e:
        lsmbs.DesignProblem(pushed_block("x_end", [entry]))
    assert words in str(e.value) and "/optimization/constraints/0" in e.value.json_path
