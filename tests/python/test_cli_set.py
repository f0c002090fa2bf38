"""`--set /json/pointer=value` on the command line. Reference: the same case file edited by hand
(the override must give the very numbers of the edited file, bit for bit)."""
import json
import subprocess

import pytest

from conftest import CLI, SPRING, run_cli


def cli(*args):
    return subprocess.run([CLI, *[str(a) for a in args], "-q"], capture_output=True, text=True)


@pytest.mark.parametrize("pointer,value,edit", [
    ("/simulation/h", "5e-4", lambda d: d["simulation"].__setitem__("h", 5e-4)),
    ("/bodies/2/mass", "0.6", lambda d: d["bodies"][2].__setitem__("mass", 0.6)),
    ("/simulation/newton", "modified", lambda d: d["simulation"].__setitem__("newton", "modified")),
])
def test_a_json_path_override_equals_the_edited_file(tmp_path, spring_doc, write_case, pointer,
                                                     value, edit):
    edit(spring_doc)
    edited = write_case(spring_doc)
    S = run_cli("sensitivity", SPRING, "--set", f"{pointer}={value}", "-o", tmp_path / "set")
    R = run_cli("sensitivity", edited, "-o", tmp_path / "edited")
    assert S["responses"] == R["responses"] and S["gradients"] == R["gradients"]
    assert S["overrides"] == {pointer: json.loads(value) if value[0].isdigit() else value}
    assert R["overrides"] == {}


def test_design_and_json_path_overrides_combine_and_simulate_records_them(tmp_path, spring_doc,
                                                                         write_case):
    spring_doc["simulation"]["h"] = 2e-3
    edited = write_case(spring_doc)
    S = run_cli("simulate", SPRING, "--set", "/simulation/h=2e-3", "--set", "k=5000",
                "-o", tmp_path / "a")
    R = run_cli("simulate", edited, "--set", "k=5000", "-o", tmp_path / "b")
    assert S["responses"] == R["responses"]
    assert S["overrides"] == {"/simulation/h": 2e-3}


@pytest.mark.parametrize("arg,words", [
    ("/simulation/hh=1e-3", ["/simulation/hh", "unknown key", "set by --set /simulation/hh=1e-3"]),
    ("/simulation/h=-1", ["/simulation/h", "positive", "set by --set /simulation/h=-1"]),
    ("/bodies/7/mass=1", ["/bodies/7", "has no /bodies/7"]),
    ("/bodies/x/mass=1", ["/bodies/x", "has no /bodies/x"]),
    ("/simulation/h/x=1", ["/simulation/h", "holds a number"]),
    ("/simulation/h=", ["expected a value"]),
    ("simulation/h=1", ["unknown design variable", "a JSON path starts with /"]),
])
def test_bad_overrides_are_input_errors_that_name_them(tmp_path, arg, words):
    p = cli("simulate", SPRING, "--set", arg, "-o", tmp_path / "out")
    assert p.returncode == 2, p.stderr
    for w in words:
        assert w in p.stderr, p.stderr
    assert not (tmp_path / "out").exists()


def test_optimize_takes_overrides_and_its_resume_refuses_other_overrides(tmp_path, spring_doc,
                                                                        write_case):
    spring_doc["optimization"] = {"objective": "mean_piston_x", "constraints": [],
                                  "stop": {"max_evaluations": 2}}
    case = write_case(spring_doc)
    out = tmp_path / "opt"
    S = run_cli("optimize", case, "--no-check", "--set", "k=6000", "--set",
                "/simulation/h=2e-3", "-o", out)
    assert S["overrides"] == {"/design/variables/0/initial": 6000.0, "/simulation/h": 2e-3}
    assert S["initial"]["design"]["k"] == 6000.0
    p = cli("optimize", case, "--resume", "--set", "k=6000", "-o", out)
    assert p.returncode == 2 and "changed" in p.stderr, p.stderr
    p = cli("optimize", case, "--resume", "--no-check", "--set", "k=6000", "--set",
            "/simulation/h=2e-3", "-o", out)
    assert p.returncode == 0, p.stderr


def test_a_resume_started_in_one_interface_ends_in_the_other_on_the_same_design(tmp_path,
                                                                               spring_doc,
                                                                               write_case):
    """The command line and Python hash a resumed run's problem with one function
    (lsmbs::resume_hash): a run interrupted on the command line after 2 evaluations and resumed
    from Python ends on the design of an uninterrupted run, and a Python run is replayed by the
    command line's --resume without a simulation, on the same design."""
    import os
    import lsmbs
    spring_doc["optimization"] = {"objective": "mean_piston_x", "constraints": [],
                                  "stop": {"max_evaluations": 5}}
    case = write_case(spring_doc)
    whole = run_cli("optimize", case, "--no-check", "-o", tmp_path / "whole")
    env = dict(os.environ, LSMBS_STOP_AFTER_EVALUATIONS="2")
    p = subprocess.run([CLI, "optimize", str(case), "--no-check", "-q", "-o",
                        str(tmp_path / "split")], capture_output=True, text=True, env=env)
    assert p.returncode == 130, p.stderr
    r = lsmbs.optimize(lsmbs.load_case(case), out_dir=str(tmp_path / "split"), resume=True,
                       check=False)
    assert r["status"] == "complete"
    S = json.loads((tmp_path / "split" / "summary.json").read_text())
    assert S["final"]["design"] == whole["final"]["design"], (S["final"], whole["final"])
    assert S["final"]["objective"] == whole["final"]["objective"]
    # Python first, then the command line replays it
    r = lsmbs.optimize(lsmbs.load_case(case), out_dir=str(tmp_path / "py"), check=False)
    # one job: Python's folder holds what the command line's does, summary.json the same keys
    # and numbers (apart from the command that ran it)
    P = json.loads((tmp_path / "py" / "summary.json").read_text())
    assert r["summary"]["final"] == P["final"]
    assert set(P) == set(whole), set(P) ^ set(whole)
    assert sorted(P["files"]) == sorted(whole["files"])
    for f in P["files"]:
        assert (tmp_path / "py" / f).is_file(), f
    for key in ("initial", "final", "responses", "stop_reason", "converged", "kkt", "status"):
        assert P[key] == whole[key], key
    S = run_cli("optimize", case, "--resume", "--no-check", "-o", tmp_path / "py")
    assert S["counts"]["simulations_this_run"] == 0
    assert S["final"]["design"] == whole["final"]["design"]


def test_python_optimize_resumes_a_run_interrupted_in_its_check_and_lists_check_warnings(
        tmp_path, spring_doc, write_case):
    """A folder whose run was interrupted during the gradient check at the initial design (no
    checkpoint; summary.json names the phase, as `lsmbs optimize` writes it on SIGINT) is started
    anew by resume=True in Python as on the command line; a check above check_warn is in the
    returned warnings and summary.json's; the dict's status is summary.json's."""
    import lsmbs
    spring_doc["optimization"] = {"objective": "mean_piston_x", "constraints": [],
                                  "stop": {"max_evaluations": 3}}
    case = write_case(spring_doc)
    out = tmp_path / "opt"
    out.mkdir()
    (out / "summary.json").write_text(json.dumps({
        "status": "interrupted", "resumable": True,
        "interrupted_phase": "gradient check at the initial design", "files": ["summary.json"]}))
    r = lsmbs.optimize(lsmbs.load_case(case), out_dir=str(out), resume=True, check_warn=1e-300,
                       check_fail=1.0)
    assert r["status"] == r["summary"]["status"] == "complete"
    assert r["gradient_check"]["verdict"] == "warn"
    assert any(w.startswith("gradient check at the initial design") for w in r["warnings"])
    S = json.loads((out / "summary.json").read_text())
    assert S["warnings"] == r["warnings"] and (out / "checkpoint.json").is_file()
