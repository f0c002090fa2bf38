"""The VTK output of a four-bar with a flexible coupler, read with VTK's own readers (what ParaView
uses): the multiblock of every instant holds every body, the rigid links are lines between their
joints at the positions of the four-bar's closed-form position analysis, and Warp By Vector
(vtkWarpVector) with total_displacement × −1 puts every body back at its placement at t = 0.

Needs VTK's Python module (scripts/setup-deps.sh --with-vtk); ctest registers it only where
`import vtk` works, and pytest skips it elsewhere."""
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

vtk = pytest.importorskip("vtk")
from vtk.util.numpy_support import vtk_to_numpy  # noqa: E402

import fourbar  # noqa: E402
from conftest import run_cli  # noqa: E402


def blocks(vtm):
    r = vtk.vtkXMLMultiBlockDataReader()
    r.SetFileName(str(vtm))
    r.Update()
    mb = r.GetOutput()
    out = {}
    for i in range(mb.GetNumberOfBlocks()):
        out[mb.GetMetaData(i).Get(vtk.vtkCompositeDataSet.NAME())] = mb.GetBlock(i)
    return mb, out


def points(grid):
    return vtk_to_numpy(grid.GetPoints().GetData())[:, :2]


def same_points(a, b):
    """Largest distance from a point of a to the nearest of b, and back (order-free)."""
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return max(d.min(axis=1).max(), d.min(axis=0).max())


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("fourbar")
    m, coupler_angle = fourbar.build()
    m.save(tmp / "fourbar.json")
    S = run_cli("simulate", tmp / "fourbar.json", "-o", tmp / "out")
    return tmp / "out", S, coupler_angle


def test_every_body_is_in_every_multiblock_and_the_links_follow_the_closed_form(run):
    out, S, coupler_angle = run
    pvd = ET.parse(out / "model.pvd").getroot()
    steps = [(float(d.get("timestep")), d.get("file")) for d in pvd.iter("DataSet")]
    assert [t for t, _ in steps] == pytest.approx([0, 0.125, 0.25, 0.375, 0.5])
    X_ref = fourbar.reference_mesh(coupler_angle)
    worst = {"crank": 0, "rocker": 0, "coupler": 0, "pins": 0}
    for t, f in steps:
        assert f in S["files"]
        _, b = blocks(out / f)
        assert set(b) == {"crank", "coupler", "rocker"}
        a, pin_b = fourbar.joints(fourbar.crank_angle(t))
        for name, ends in (("crank", [np.zeros(2), a]), ("rocker", [np.array([fourbar.D, 0]), pin_b])):
            g = b[name]
            assert g.GetNumberOfCells() == 1 and g.GetCellType(0) == vtk.VTK_LINE
            worst[name] = max(worst[name], same_points(points(g), np.array(ends)))
        c = b["coupler"]
        assert c.GetNumberOfCells() == fourbar.NX * fourbar.NY and c.GetCellType(0) == vtk.VTK_QUAD
        x = points(c)
        X = x - vtk_to_numpy(c.GetPointData().GetArray("total_displacement"))[:, :2]
        worst["coupler"] = max(worst["coupler"], same_points(X, X_ref))
        # the coupler's pin nodes sit on the crank's and rocker's pins
        worst["pins"] = max(worst["pins"], np.linalg.norm(x - a, axis=1).min(),
                            np.linalg.norm(x - pin_b, axis=1).min())
    # crank: driven, exact to the constraint tolerance (measured 0); rocker and pins: the
    # rigid-link closed form, off by the coupler's elastic elongation (steel pinned at single
    # nodes, 1 rev/s: measured 3.7e-8 m); the reference mesh: measured 3e-17 m
    assert worst["crank"] < 1e-10, worst
    assert worst["rocker"] < 1e-7, worst
    assert worst["pins"] < 1e-7, worst
    assert worst["coupler"] < 1e-12, worst


def test_warp_by_total_displacement_times_minus_one_gives_the_placement_at_t0(run):
    out, _, coupler_angle = run
    pvd = ET.parse(out / "model.pvd").getroot()
    last = max((float(d.get("timestep")), d.get("file")) for d in pvd.iter("DataSet"))[1]
    mb, _ = blocks(out / last)
    warp = vtk.vtkWarpVector()  # ParaView's Warp By Vector
    warp.SetInputData(mb)
    warp.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_POINTS,
                                "total_displacement")
    warp.SetScaleFactor(-1.0)
    warp.Update()
    res = warp.GetOutputDataObject(0)  # a multiblock in, a multiblock out
    got = {res.GetMetaData(i).Get(vtk.vtkCompositeDataSet.NAME()): points(res.GetBlock(i))
           for i in range(res.GetNumberOfBlocks())}
    a0, b0 = fourbar.joints(0.0)
    assert same_points(got["coupler"], fourbar.reference_mesh(coupler_angle)) < 1e-12
    assert same_points(got["crank"], np.array([[0, 0], a0])) < 1e-12
    assert same_points(got["rocker"], np.array([[fourbar.D, 0], b0])) < 1e-12
    # and the warped coupler moved: the motion was not zero
    assert same_points(points(blocks(out / last)[1]["coupler"]), got["coupler"]) > 0.01


def test_the_per_body_series_read_with_the_unstructured_grid_reader(run):
    out, _, _ = run
    pvd = ET.parse(out / "rocker.pvd").getroot()
    for d in pvd.iter("DataSet"):
        r = vtk.vtkXMLUnstructuredGridReader()
        r.SetFileName(str(out / d.get("file")))
        r.Update()
        x = points(r.GetOutput())
        _, pin_b = fourbar.joints(fourbar.crank_angle(float(d.get("timestep"))))
        assert same_points(x, np.array([[fourbar.D, 0], pin_b])) < 1e-7
        assert np.linalg.norm(x[1] - x[0]) == pytest.approx(fourbar.R4, abs=1e-12)  # rigid
        assert math.isclose(np.abs(vtk_to_numpy(
            r.GetOutput().GetPointData().GetArray("elastic_displacement"))).max(), 0)
