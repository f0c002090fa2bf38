"""Errors carry the command line's message and JSON path; bad types give TypeError; progress
callbacks run during long runs; an exception or Ctrl-C in the middle of a run stops it cleanly
and the next run is unaffected."""
import os
import signal
import subprocess
import sys
import textwrap
import threading

import pytest

import lsmbs
from conftest import CLI, SPRING


def cli_error(path):
    p = subprocess.run([CLI, "simulate", str(path), "-o", str(path) + ".out", "-q"],
                       capture_output=True, text=True)
    assert p.returncode == 2
    return p.stderr.strip().removeprefix("lsmbs: error: ")


def test_invalid_case_raises_error_with_the_json_path(spring_doc, write_case):
    spring_doc["simulation"]["h"] = -1
    path = write_case(spring_doc)
    with pytest.raises(lsmbs.Error) as e:
        lsmbs.load_case(str(path))
    assert e.value.json_path == "/simulation/h"
    assert e.value.file == str(path)
    assert str(e.value) == cli_error(path)  # the command line's message, word for word
    assert isinstance(e.value, ValueError)


def test_library_errors_by_name_are_located_in_the_case(spring_doc, write_case):
    del spring_doc["design"]
    case = lsmbs.load_case(str(write_case(spring_doc)))
    with pytest.raises(lsmbs.Error) as e:
        lsmbs.sensitivity(case)
    assert e.value.json_path == "/design"


def test_missing_file():
    with pytest.raises(lsmbs.Error, match="no_such_case.json"):
        lsmbs.load_case("no_such_case.json")


def test_bad_types_raise_type_error():
    case = lsmbs.load_case(str(SPRING))
    with pytest.raises(TypeError):
        lsmbs.simulate("not a case")
    with pytest.raises(TypeError):
        lsmbs.sensitivity(case, method=3)
    with pytest.raises(TypeError):
        case.simulation.h = "small"
    with pytest.raises(ValueError, match="expected one of"):
        lsmbs.sensitivity(case, method="adjoint-magic")
    with pytest.raises(KeyError):
        case.parameters["no.such"] = 1.0
    with pytest.raises(ValueError, match="design variable 'k'"):
        case.parameters["spring.stiffness"] = 1.0  # bound to a design variable


def test_options_set_from_python_are_checked_as_the_case_file_is(spring_doc, write_case):
    # the same value in the JSON: the command line's message and path
    for h in (0.0, 1.0, 0.0011, float("inf")):
        case = lsmbs.load_case(str(SPRING))
        case.simulation.h = h
        with pytest.raises(lsmbs.Error) as e:
            lsmbs.simulate(case)
        assert e.value.json_path == "/simulation/h", h
        if h in (1.0, 0.0011):  # the loader's own message for the edited file
            spring_doc["simulation"]["h"] = h
            assert str(e.value).split(": ", 1)[1] == cli_error(write_case(spring_doc)).split(": ", 1)[1]
    case = lsmbs.load_case(str(SPRING))
    case.simulation.k = float("inf")
    with pytest.raises(lsmbs.Error, match="/simulation/k"):
        lsmbs.sensitivity(case)


def test_none_and_wrong_types_are_type_errors():
    for f in (lsmbs.simulate, lsmbs.sensitivity, lsmbs.geometry, lsmbs.optimize, lsmbs.DesignProblem):
        with pytest.raises(TypeError):
            f(None)
    case = lsmbs.load_case(str(SPRING))
    for bad in ("kc", {1: 2.0}, {"k": None}, [[4000, 20]], {"k", "c"}):
        with pytest.raises(TypeError):
            lsmbs.sensitivity(case, design=bad)


def test_model_parameters_are_range_checked():
    case = lsmbs.load_case(str(SPRING))
    for name, v in (("piston.mass", -1.0), ("piston.mass", float("nan")), ("crank.inertia", -1e-3)):
        with pytest.raises(ValueError, match="model parameter"):
            case.parameters[name] = v
    rod = lsmbs.load_case(str(SPRING.parents[1] / "slider_crank" / "slider_crank_1hole_coarse.json"))
    for name, v in (("rod.E", 0.0), ("rod.nu", 0.5), ("rod.rho", -1.0), ("rod.thickness", -1e-3)):
        with pytest.raises(ValueError, match="model parameter"):
            rod.parameters[name] = v


def test_unknown_optimizer_is_refused_at_its_path():
    case = lsmbs.load_case(str(SPRING.parents[1] / "slider_crank" / "slider_crank_1hole_coarse.json"))
    with pytest.raises(lsmbs.Error) as e:
        lsmbs.optimize(case, optimizer="mmaa")
    assert e.value.json_path == "/optimization/optimizer"


def test_step_lost_in_round_off_is_refused():
    case = lsmbs.load_case(str(SPRING))
    for m in ("fd-forward", "semi-analytical"):
        with pytest.raises(lsmbs.Error, match="delta"):
            lsmbs.sensitivity(case, method=m, delta=1e-17)


def test_failed_evaluation_is_nan_in_complete_shapes():
    case = lsmbs.load_case(str(SPRING.parents[1] / "slider_crank" / "slider_crank_1hole_coarse.json"))
    case.simulation.max_iter = 1
    case.simulation.max_halvings = 0
    prob = lsmbs.DesignProblem(case)
    e = prob.evaluate([0.02])
    assert not e["ok"]
    m, n = prob.num_constraints, prob.num_variables
    assert e["constraints"].shape == (m,) and e["upper"].shape == (m,)
    assert e["constraint_gradient"].shape == (m, n) and e["objective_gradient"].shape == (n,)
    import numpy as np
    for k in ("constraints", "constraint_gradient", "objective_gradient"):
        assert np.isnan(e[k]).all(), k
    assert np.isfinite(e["upper"]).all()


def test_progress_callback_sees_the_run():
    case = lsmbs.load_case(str(SPRING))
    seen = []
    lsmbs.simulate(case, progress=seen.append)
    assert seen, "no progress report"
    ts = [p["t"] for p in seen]
    assert ts == sorted(ts) and 0 < ts[-1] <= 0.25 + 1e-12
    assert all(p["t_end"] == 0.25 for p in seen)


def test_exception_in_callback_stops_the_run_and_the_next_run_is_clean():
    case = lsmbs.load_case(str(SPRING))
    case.simulation.h = 1e-5  # a long run: 25,000 steps

    def stop(p):
        if p["t"] > 0.01:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        lsmbs.sensitivity(case, progress=stop)
    case.simulation.h = 1e-3
    r = lsmbs.sensitivity(case)
    assert r.status == "complete"


def test_exception_in_callback_stops_an_idas_run():
    case = lsmbs.load_case(str(SPRING))

    def stop(p):  # at the first report (the only one the 50 ms throttle guarantees)
        raise KeyboardInterrupt

    for method in ("idas", "idas-adjoint"):
        with pytest.raises(KeyboardInterrupt):
            lsmbs.sensitivity(case, method=method, progress=stop)
    assert lsmbs.sensitivity(case, method="idas").status == "complete"


def test_ctrl_c_stops_a_run_cleanly(tmp_path):
    # a child process that runs a long simulation; SIGINT once it is running
    script = textwrap.dedent(f"""
        import sys, lsmbs
        case = lsmbs.load_case({str(SPRING)!r})
        case.simulation.h = 1e-6
        started = False
        def progress(p):
            global started
            if not started:
                started = True
                print("running", flush=True)
        try:
            lsmbs.simulate(case, progress=progress)
        except KeyboardInterrupt:
            print("interrupted", flush=True)
            r = lsmbs.simulate(lsmbs.load_case({str(SPRING)!r}))
            print(r.status, flush=True)
    """)
    env = dict(os.environ)
    p = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True, env=env)
    assert p.stdout.readline().strip() == "running"
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    assert p.returncode == 0
    assert out.split() == ["interrupted", "complete"]


def test_import_on_an_interpreter_without_numpy_names_the_interpreter_to_use():
    """`python3 -S` has no site packages, so no NumPy: the import says which interpreter lsmbs was
    built for instead of a bare ModuleNotFoundError (the python3 first on PATH may be a pyenv or
    conda one without Debian's NumPy)."""
    import subprocess
    import sys
    from lsmbs import _build_info
    p = subprocess.run([sys.executable, "-S", "-c", "import lsmbs"], capture_output=True,
                       text=True, env=dict(os.environ))
    assert p.returncode != 0
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith("ImportError: lsmbs was built for " + _build_info.PYTHON), last
    assert "has no NumPy" in last and sys.executable in last, last
