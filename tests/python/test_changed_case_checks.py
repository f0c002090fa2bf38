"""A case changed from Python meets the command line's checks: a simulation option or a model
parameter set as an attribute is refused before any run, with the message that the command line
gives for the same value set with `--set` (the reference, run here), never a NaN response in a run
reported complete or an error that blames another element."""
import json
import math
import subprocess

import numpy as np
import pytest

import lsmbs
from conftest import CLI, ROOT, SPRING

COARSE = ROOT / "data" / "slider_crank" / "slider_crank_1hole_coarse.json"
SET_BY = " (the value was set by --set "


def cli_refusal(tmp_path, case, *sets, command="simulate"):
    """The command line's message for the case with the values set (exit 2 required), without
    the note naming the --set that gave the value (Python set it as an attribute)."""
    args = [CLI, command, str(case), "-o", str(tmp_path / "cli"), "-q", "--overwrite"]
    for s in sets:
        args += ["--set", s]
    p = subprocess.run(args, capture_output=True, text=True)
    assert p.returncode == 2, (args, p.returncode, p.stderr)
    msg = p.stderr.strip().removeprefix("lsmbs: error: ")
    return msg.split(SET_BY)[0] if SET_BY in msg else msg


def reason_of(message, case, path):
    """The message without its "file: json path: " prefix."""
    prefix = f"{case}: {path}: "
    assert message.startswith(prefix), (message, prefix)
    return message[len(prefix):]


@pytest.fixture
def spring_with_objective(spring_doc, write_case):
    """The shipped spring case with an optimization section (its objective only)."""
    spring_doc["optimization"] = {"objective": "energy_integral", "optimizer": "mma"}
    return write_case(spring_doc)


def runs():
    """Every entry point of the module that simulates a loaded case, by the command that does
    the same on the command line."""
    return {
        "simulate": lambda c: lsmbs.simulate(c),
        "sensitivity": lambda c: lsmbs.sensitivity(c),
        "static": lambda c: lsmbs.static(c),
        "evaluate": lambda c: lsmbs.DesignProblem(c).evaluate(None),
        "optimize": lambda c: lsmbs.optimize(c, check=False),
    }


def test_t_end_below_a_response_window_is_refused_as_on_the_command_line(
        tmp_path, spring_with_objective):
    # the spring case's max_side_force has the window [0.1, 0.25] s: a run to 0.05 s has no step
    # in it (the command line refuses it; a run would report complete with a NaN response)
    path = spring_with_objective
    for name, run in runs().items():
        case = lsmbs.load_case(str(path))
        problem = lsmbs.DesignProblem(case) if name == "evaluate" else None
        case.simulation.t_end = 0.05
        with pytest.raises(lsmbs.Error) as e:
            problem.evaluate(None) if problem else run(case)
        command = {"evaluate": "optimize"}.get(name, name)
        expected = cli_refusal(tmp_path, path, "/simulation/t_end=0.05", command=command)
        assert str(e.value) == expected, name
        assert e.value.json_path == "/output/responses/3/window"
    # the case is usable again once the value is put back: the same responses as a fresh case
    case.simulation.t_end = 0.25
    r = lsmbs.simulate(case)
    fresh = lsmbs.simulate(lsmbs.load_case(str(path)))
    assert r.status == fresh.status == "complete"
    for k, v in fresh.responses.items():
        assert np.array_equal(r.responses[k], v), k


@pytest.mark.parametrize("case_file,parameter,pointer", [
    (SPRING, "crank.mass", "/bodies/0/mass"),
    (SPRING, "crank.inertia", "/bodies/0/inertia"),
    (SPRING, "spring.free_length", "/forces/0/free_length"),
    (COARSE, "rod.E", "/bodies/2/material/E"),
    (COARSE, "rod.thickness", "/bodies/2/thickness"),
])
def test_a_huge_parameter_is_refused_at_its_entry_as_on_the_command_line(
        tmp_path, case_file, parameter, pointer):
    # 1e308 is admissible as a number but overflows at the start: the command line names the entry
    # that holds it and its parameters; Python ran into a singular matrix blaming another element
    # ("constraint 'cylinder' has no mass" for the crank's mass) or a run reported failed
    expected = cli_refusal(tmp_path, case_file, f"{pointer}=1e308")
    for run in (lsmbs.simulate, lsmbs.sensitivity):
        case = lsmbs.load_case(str(case_file))
        case.parameters[parameter] = 1e308
        with pytest.raises(lsmbs.Error) as e:
            run(case)
        assert str(e.value) == expected, run
        assert pointer.startswith(e.value.json_path)


@pytest.mark.parametrize("case_file,parameter,pointer,value", [
    (SPRING, "piston.mass", "/bodies/2/mass", -1),
    (SPRING, "crank.inertia", "/bodies/0/inertia", -1e-3),
    (SPRING, "spring.free_length", "/forces/0/free_length", -1),
    (COARSE, "rod.thickness", "/bodies/2/thickness", -1e-3),
    (COARSE, "rod.thickness", "/bodies/2/thickness", 0),
    (COARSE, "rod.rho", "/bodies/2/material/rho", -1),
    (COARSE, "rod.E", "/bodies/2/material/E", 0),
    (COARSE, "rod.nu", "/bodies/2/material/nu", 0.5),
    (COARSE, "gas.area", "/forces/0/area", 0),
    (COARSE, "gas.area", "/forces/0/area", -1),
])
def test_an_out_of_range_parameter_is_refused_at_its_place_in_the_case(
        tmp_path, case_file, parameter, pointer, value):
    # the command line's place (file, JSON path) and words (up to the value it shows)
    cli = cli_refusal(tmp_path, case_file, f"{pointer}={json.dumps(value)}")
    case = lsmbs.load_case(str(case_file))
    with pytest.raises(lsmbs.Error) as e:
        case.parameters[parameter] = float(value)
    assert e.value.file == str(case_file)
    assert e.value.json_path == pointer
    expected = reason_of(cli, case_file, pointer).split(", got ")[0]
    assert e.value.reason.split(" (model parameter")[0] == expected
    assert f"model parameter '{parameter}'" in e.value.reason  # and Python's own name of it
    assert isinstance(e.value, ValueError)


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_a_non_finite_parameter_is_refused_at_its_place_in_the_case(tmp_path, value):
    # JSON has no non-finite number: the command line refuses the text at the same place, and the
    # loader's words for a non-finite number are "expected a finite number"
    cli = cli_refusal(tmp_path, SPRING, "/bodies/2/mass=NaN")
    assert cli.startswith(f"{SPRING}: /bodies/2/mass: ")
    case = lsmbs.load_case(str(SPRING))
    with pytest.raises(lsmbs.Error) as e:
        case.parameters["piston.mass"] = value
    assert e.value.json_path == "/bodies/2/mass"
    assert e.value.reason.startswith("expected a finite number")
    assert case.parameters["piston.mass"] == 0.456  # unchanged


@pytest.mark.parametrize("option,value", [("zeta", 1e300), ("k", 1e-300)])
def test_a_scaling_far_from_the_automatic_one_is_refused_as_on_the_command_line(
        tmp_path, option, value):
    # zeta = 1e300 from Python gave a side force of 4.6e277 N in a run reported complete
    expected = cli_refusal(tmp_path, SPRING, f"/simulation/{option}={value!r}")
    case = lsmbs.load_case(str(SPRING))
    setattr(case.simulation, option, value)
    with pytest.raises(lsmbs.Error) as e:
        lsmbs.simulate(case)
    assert str(e.value) == expected
    assert e.value.json_path == f"/simulation/{option}"


def test_projection_switched_on_from_python_checks_the_placement(tmp_path, write_case):
    # a bar drawn 0.5 m away from its pivot, in a case that does not project its initial state:
    # switching the projection on from Python moved the bar silently; the command line refuses
    doc = {
        "name": "misplaced",
        "bodies": [{"name": "bar", "type": "rigid", "position": [0.5, 0], "mass": 1,
                    "inertia": 0.1}],
        "joints": [{"name": "pivot", "type": "revolute", "a": {"body": "bar", "at": [0, 0]},
                    "b": {"ground": [0, 0]}}],
        "gravity": [0, -9.81],
        "simulation": {"t_end": 0.01, "h": 0.001, "project_initial": False},
        "output": {"measures": [{"name": "angle", "type": "angle", "body": "bar"}],
                   "responses": [{"name": "final_angle", "measure": "angle",
                                  "aggregate": "final"}]},
    }
    path = write_case(doc)
    expected = cli_refusal(tmp_path, path, "/simulation/project_initial=true")
    assert "does not satisfy the joints" in expected
    case = lsmbs.load_case(str(path))
    case.simulation.project_initial = True
    with pytest.raises(lsmbs.Error) as e:
        lsmbs.simulate(case)
    assert str(e.value) == expected
    assert e.value.json_path == "/bodies/0"


def test_geometry_checks_the_changed_case_as_lsmbs_geometry_does(tmp_path):
    # `lsmbs geometry` loads the case, so it refuses what the loader refuses
    expected = cli_refusal(tmp_path, COARSE, "/bodies/2/thickness=1e308", command="geometry")
    case = lsmbs.load_case(str(COARSE))
    case.parameters["rod.thickness"] = 1e308
    with pytest.raises(lsmbs.Error) as e:
        lsmbs.geometry(case)
    assert str(e.value) == expected


def test_iteration_cap_beyond_the_case_files_bound_is_refused_at_its_path(tmp_path):
    cli = cli_refusal(tmp_path, SPRING, "/simulation/max_iter=500000000")
    assert cli.startswith(f"{SPRING}: /simulation/max_iter: ")
    case = lsmbs.load_case(str(SPRING))
    case.simulation.max_iter = 500000000
    with pytest.raises(lsmbs.Error) as e:
        lsmbs.simulate(case)
    assert e.value.json_path == "/simulation/max_iter"
    assert "100000000" in e.value.reason


@pytest.mark.parametrize("option,value", [("rtol", 2.0), ("rtol", 0.0), ("atol", -1.0)])
def test_idas_tolerances_are_refused_as_the_command_lines_flags(tmp_path, option, value):
    # rtol = 2 ran (IDAS accepts any positive tolerance) and atol = -1 was replaced by rtol
    p = subprocess.run([CLI, "sensitivity", str(SPRING), "-o", str(tmp_path / "cli"), "-q",
                        "--method", "idas", f"--{option}", repr(value)],
                       capture_output=True, text=True)
    assert p.returncode == 2, p.stderr
    cli = p.stderr.strip().removeprefix("lsmbs: error: ")
    assert cli.startswith(f"--{option} ")
    with pytest.raises(ValueError) as e:
        lsmbs.sensitivity(lsmbs.load_case(str(SPRING)), method="idas", **{option: value})
    assert str(e.value).startswith(f"{option} ")
    assert str(e.value).split(": ", 1)[1] == cli.split(": ", 1)[1]


def test_an_optimizer_without_the_cases_move_limit_is_refused(tmp_path):
    # the coarse connecting rod sets a move_limit, which only mma-svanberg has: the command line
    # refuses --optimizer mma; Python ran mma and dropped the move limit without a word
    p = subprocess.run([CLI, "optimize", str(COARSE), "-o", str(tmp_path / "cli"), "-q",
                        "--optimizer", "mma"], capture_output=True, text=True)
    assert p.returncode == 2, p.stderr
    cli = p.stderr.strip().removeprefix("lsmbs: error: ")
    assert cli.startswith("--optimizer mma: ")
    with pytest.raises(lsmbs.Error) as e:
        lsmbs.optimize(lsmbs.load_case(str(COARSE)), optimizer="mma", check=False,
                       out_dir=str(tmp_path / "py"))
    assert str(e.value) == "optimizer='mma': " + cli.removeprefix("--optimizer mma: ")
    assert not (tmp_path / "py").exists()  # refused before the output folder is made
