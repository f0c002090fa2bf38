"""Names built in Python are data: a measure, response, body or case name holding a gnuplot or
shell command after a newline, quotes, markup or '$' pairs runs nothing and writes nothing outside
the output folder, through the module's simulate and geometry and through lsmbs.plot (matplotlib
text, not mathtext). The reference: no file named MARK exists anywhere afterwards, and every file
written parses (JSON, XML, CSV, PNG)."""
import csv
import json
import os
import xml.etree.ElementTree as ET

import pytest

import lsmbs
from lsmbs import circle, nearest, rectangle

HOSTILE = ["x\nsystem 'touch MARK'\n#", "$(touch MARK)`touch MARK`", "a'b\"c\\d",
           "<x>&amp;]]>", "$\\alpha$ $\\notacommand$", "µ 日本 \u202eRTL"]


def plate(name):
    m = lsmbs.ModelBuilder(name + " case")
    m.flexible_body(name + " plate", rectangle((0, 0), (0.2, 0.05), (8, 2)), E=7e10, nu=0.3,
                    rho=2700, thickness=0.001)
    m.clamp(name + " clamp", name + " plate", "left")
    m.rigid_body(name + " mass", position=(0.3, 0), mass=1, inertia=0.01)
    m.measure(name + " tip", "position", point=nearest(name + " plate", (0.2, 0.05)))
    m.response(name + " final", name + " tip.y", "final")
    r = m.variable(name + " r", 0.01, 0.005, 0.015)
    m.features(name + " plate", [circle(name + " hole", 0.1, 0.025, r)])
    m.output(vtu_stride=1)
    m.simulation(t_end=0.002, h=0.0005)
    return m.build()


@pytest.mark.parametrize("name", HOSTILE)
def test_names_built_in_python_are_never_run(tmp_path, name, monkeypatch):
    monkeypatch.chdir(tmp_path)
    case = plate(name)
    out = tmp_path / "out"
    r = lsmbs.simulate(case, out_dir=str(out))
    lsmbs.geometry(case)
    import matplotlib
    matplotlib.use("Agg")
    from lsmbs import plot
    ax = plot.history(r)
    ax.figure.savefig(tmp_path / "out" / "mpl.png")
    found = [os.path.join(d, f) for d, _, fs in os.walk(tmp_path) for f in fs if "MARK" == f]
    assert not found, found
    assert sorted(os.listdir(tmp_path)) == ["out"]
    for d, _, files in os.walk(out):
        for f in files:
            p = os.path.join(d, f)
            if f.endswith((".vtu", ".vtm", ".pvd")):
                ET.parse(p)
            elif f.endswith(".csv"):
                with open(p, newline="", encoding="utf-8") as fh:
                    assert len({len(row) for row in csv.reader(fh)}) == 1
            elif f.endswith(".json"):
                json.load(open(p, encoding="utf-8"))
            elif f.endswith(".png"):
                from PIL import Image
                Image.open(p).load()
