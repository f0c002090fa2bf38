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


def test_invalid_option_is_refused_at_run_time():
    case = lsmbs.load_case(str(SPRING))
    case.simulation.h = 0.0
    r = lsmbs.simulate(case)
    assert r.status == "failed"
    assert "h:" in r.report()


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
