"""Shared fixtures: the repository root, the lsmbs command line (the reference the Python results
are compared with), and temporary cases."""
import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(os.environ.get("LSMBS_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
CLI = os.environ.get("LSMBS_CLI", str(ROOT / "build" / "src" / "lsmbs"))
SPRING = ROOT / "data" / "slider_crank_rigid" / "slider_crank_spring.json"


def run_cli(*args, exit_codes=(0,)):
    """Runs the command line; returns its summary.json (the folder is the -o argument)."""
    args = [str(a) for a in args]
    quiet = [] if args[0] == "verify" else ["-q"]  # verify prints its verdicts
    p = subprocess.run([CLI, *args, *quiet], capture_output=True, text=True)
    assert p.returncode in exit_codes, p.stderr
    out = args[args.index("-o") + 1]
    return json.loads((pathlib.Path(out) / "summary.json").read_text())


@pytest.fixture
def spring_doc():
    return json.loads(SPRING.read_text())


@pytest.fixture
def write_case(tmp_path):
    """Writes a case document next to the shipped spring case's folder layout (no relative files)."""
    def write(doc, name="case.json"):
        p = tmp_path / name
        p.write_text(json.dumps(doc))
        return p
    return write
