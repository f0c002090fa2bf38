"""Threads that share one loaded case: every run gives the result of its own design, bit for bit
the result of the same runs one after the other (the reference). A run reads the model parameters
the case holds and the module releases the GIL while it runs; a new user's 20-design sweep from two
threads sharing one case got the other thread's results, marked complete (a mass of 0.265166 kg
instead of 0.269081 kg). Runs on one case now take turns (Study::evaluation_mutex)."""
import threading

import numpy as np
import pytest

import lsmbs
from conftest import ROOT, SPRING

HOLE = ROOT / "data" / "slider_crank" / "slider_crank_1hole_coarse.json"


def designs(case, n):
    """n designs spread over the box of the case's variables (each one different)."""
    lo, up = np.asarray(case.lower), np.asarray(case.upper)
    return [lo + (up - lo) * (0.15 + 0.7 * k / (n - 1)) for k in range(n)]


def assert_same(a, b):
    """Results bit for bit equal: dicts of floats or arrays (per-step responses)."""
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def in_two_threads(run, points):
    """run(point) for every point, half of them in each of two threads; results by index."""
    out, errors = [None] * len(points), []

    def worker(ks):
        try:
            for k in ks:
                out[k] = run(points[k])
        except Exception as e:  # noqa: BLE001 - reported below
            errors.append(e)

    threads = [threading.Thread(target=worker, args=(range(i, len(points), 2),)) for i in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    return out


def same_in_two_threads(run, points):
    """run(point) -> (values, gradients) for every point, one after the other and in two threads:
    bit for bit the same. Returns the sequential results."""
    sequential = [run(p) for p in points]
    parallel = in_two_threads(run, points)
    for (v0, g0), (v1, g1) in zip(sequential, parallel):
        assert_same(v0, v1)
        assert_same(g0, g1)
    return sequential


def test_two_threads_sharing_a_case_get_their_own_sensitivities():
    case = lsmbs.load_case(str(SPRING))
    points = designs(case, 10)

    def run(p):
        r = lsmbs.sensitivity(case, design=p)
        assert r.status == "complete"
        return r.values, r.gradients

    sequential = same_in_two_threads(run, points)
    # the designs differ, so a run on another's design could not pass the comparison above
    assert len({v["energy_integral"] for v, _ in sequential}) == len(points)


def test_two_threads_sharing_a_case_get_their_own_simulations_and_masses():
    case = lsmbs.load_case(str(HOLE))
    case.simulation.t_end = 10 * case.simulation.h  # a short run: the mass and a few steps
    points = designs(case, 8)

    def run(p):
        s = lsmbs.simulate(case, design=p)
        assert s.status == "complete"
        g = lsmbs.geometry(case, design=p)
        return s.responses, {b: v["mass"] for b, v in g.items()}

    sequential = [run(p) for p in points]
    parallel = in_two_threads(run, points)
    for (r0, m0), (r1, m1) in zip(sequential, parallel):
        assert_same(r0, r1)
        assert m0 == m1
    assert len({tuple(m.values()) for _, m in sequential}) == len(points)


def test_two_threads_sharing_a_design_problem_evaluate_their_own_points(spring_doc, write_case):
    spring_doc["optimization"] = {"objective": "energy_integral",
                                  "constraints": [{"response": "mean_piston_x", "upper": 1.0}]}
    case = lsmbs.load_case(str(write_case(spring_doc)))
    prob = lsmbs.DesignProblem(case)
    points = designs(case, 8)
    reference = lsmbs.DesignProblem(lsmbs.load_case(str(write_case(spring_doc, "ref.json"))))
    sequential = [reference.evaluate(p)["objective"] for p in points]
    parallel = in_two_threads(lambda p: prob.evaluate(p)["objective"], points)
    assert parallel == sequential


def test_amg_runs_in_two_threads_give_the_runs_one_after_the_other():
    """The AMG solver (hypre, whose global state every call reaches under one process-wide lock)
    in two threads at once: each thread runs its own case of the solid arm, so the runs overlap,
    and each run's direct sensitivities solve on two threads of their own. Every response and
    gradient is bit for bit the run's one after the other."""
    solid_arm = ROOT / "data" / "spatial" / "solid_arm.json"
    cases = [lsmbs.load_case(str(solid_arm)) for _ in range(2)]
    try:
        for c in cases:
            c.simulation.linear_solver = "amg"
    except ValueError:
        pytest.skip("this build of lsmbs has no hypre")
    for c in cases:
        c.simulation.t_end = 5 * c.simulation.h
    # point k runs on case k % 2: in_two_threads gives the even points to one thread
    points = [(k % 2, p) for k, p in enumerate(designs(cases[0], 4))]

    def run(point):
        k, p = point
        r = lsmbs.sensitivity(cases[k], design=p)
        assert r.status == "complete", r.message
        assert r.summary["primal"]["linear_solver"] == "amg"
        assert r.summary["primal"]["linear_iterations"] > 0
        return r.values, r.gradients

    sequential = same_in_two_threads(run, points)
    assert len({v["plate_mass"] for v, _ in sequential}) == len(points)
