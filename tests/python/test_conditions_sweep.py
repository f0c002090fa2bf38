"""Service conditions built with the ModelBuilder, and lsmbs.sweep.

Reference: the closed form of an undamped mass on a spring, x(t) = L + (x0 - L) cos(sqrt(k/m) t),
under each condition's mass (generalized-alpha with rho_inf = 1 and 2000 steps per second: its
phase error at t = 1 s is about (omega h)^2 omega t / 12, 1e-7 of the amplitude here), its
derivative with respect to k, and central differences of the combined responses.
"""
import math

import numpy as np
import pandas
import pytest

import lsmbs
from lsmbs import at, ground

X0, L, T = 0.51, 0.5, 1.0
MASSES = {"light": 2.0, "heavy": 5.0}


def exact(k, m, free=L):
    w = math.sqrt(k / m)
    return free + (X0 - free) * math.cos(w * T)


def exact_dk(k, m, free=L):
    w = math.sqrt(k / m)
    return -(X0 - free) * math.sin(w * T) * T / (2 * math.sqrt(k * m))


def block(ks=2000.0):
    m = lsmbs.ModelBuilder("payloads")
    m.rigid_body("block", position=(X0, 0), mass=1.0)
    m.prismatic("slide", at("block"), (1, 0))
    m.variable("k", initial=200, lower=50, upper=400)
    m.spring_damper("spring", at("block"), ground((0, 0)), stiffness=200, damping=0.0, free_length=L)
    m.bind_parameter("spring.stiffness", "k")
    m.measure("x", "position", point=at("block"))
    m.response("x_end", "x.x", "final")
    m.simulation(t_end=T, h=5e-4, rho_inf=1.0)
    for name, mass in MASSES.items():
        m.condition(name, set={"/bodies/block/mass": mass})
    m.combined("mean_end", ["light.x_end", "heavy.x_end"], "sum", weights=[0.5, 0.5])
    m.combined("worst_end", "x_end", "ks", ks=ks)
    return m.build()


def test_conditions_are_named_and_match_the_closed_form():
    case = block()
    assert list(case.conditions) == ["light", "heavy"]
    r = lsmbs.simulate(case)
    assert r.status == "complete"
    got = r.responses
    for name, mass in MASSES.items():
        assert got[name + ".x_end"] == pytest.approx(exact(200, mass), abs=2e-6)
    assert got["mean_end"] == pytest.approx(0.5 * (got["light.x_end"] + got["heavy.x_end"]), rel=1e-15)
    top = max(got["light.x_end"], got["heavy.x_end"])
    assert top <= got["worst_end"] <= top + math.log(2) / 2000.0


def test_gradients_of_the_combinations_match_the_closed_form_and_central_differences():
    case = block(ks=200.0)
    s = lsmbs.sensitivity(case)
    assert s.status == "complete"
    g = {name: float(s.gradients[name][0]) for name in s.gradients}
    for name, mass in MASSES.items():
        assert g[name + ".x_end"] == pytest.approx(exact_dk(200, mass), rel=1e-3)
    d = 1e-3  # central differences of the combined responses over simulate runs
    plus = lsmbs.simulate(case, design={"k": 200 + d}).responses
    minus = lsmbs.simulate(case, design={"k": 200 - d}).responses
    for name in ("mean_end", "worst_end"):
        fd = (plus[name] - minus[name]) / (2 * d)
        assert g[name] == pytest.approx(fd, rel=1e-5, abs=1e-9), name


def test_a_grid_sweep_is_the_closed_form_and_the_file_pandas_reads(tmp_path):
    case = block()
    frame = lsmbs.sweep(case, axes={"k": (100, 300, 3), "spring.free_length": (0.49, 0.5, 2)},
                        gradients=True, out_dir=tmp_path / "sweep")
    assert len(frame) == 6 and list(frame["status"]) == ["complete"] * 6
    assert list(frame["k"]) == [100, 100, 200, 200, 300, 300]  # the last axis fastest
    for _, row in frame.iterrows():
        for name, mass in MASSES.items():
            free = row["spring.free_length"]
            assert row[name + ".x_end"] == pytest.approx(exact(row["k"], mass, free), abs=2e-6)
            assert row["d(%s.x_end)/d(k)" % name] == pytest.approx(
                exact_dk(row["k"], mass, free), rel=2e-3, abs=1e-9)
    csv = pandas.read_csv(tmp_path / "sweep" / "sweep.csv")  # as is, no options
    numbers = [c for c in frame.columns if c not in ("status", "message")]
    np.testing.assert_array_equal(csv[numbers].to_numpy(float), frame[numbers].to_numpy(float))
    assert frame.attrs["summary"]["points"]["completed"] == 6


def test_a_latin_hypercube_has_one_point_per_stratum_of_every_axis():
    case = block()
    box = {"k": (100.0, 300.0), "spring.free_length": (0.49, 0.5)}
    a = lsmbs.sweep(case, lhs=box, samples=5, seed=3)
    for name, (lo, hi) in box.items():
        strata = sorted(int((x - lo) / (hi - lo) * 5) for x in a[name])
        assert strata == [0, 1, 2, 3, 4], name
    b = lsmbs.sweep(case, lhs=box, samples=5, seed=3)
    np.testing.assert_array_equal(a["k"], b["k"])  # the seed makes it reproducible
    c = lsmbs.sweep(case, lhs=box, samples=5, seed=4)
    assert not np.array_equal(a["k"], c["k"])


def test_a_sweep_over_nothing_known_is_refused():
    with pytest.raises(lsmbs.Error, match="no_such"):
        lsmbs.sweep(block(), axes={"no_such": (0, 1, 2)})
    with pytest.raises(TypeError, match="lower, upper, points"):
        lsmbs.sweep(block(), axes={"k": (0, 1)})


def test_every_output_folder_may_be_a_path(tmp_path):
    """out_dir takes a pathlib.Path as it takes a str (it raised TypeError for simulate, static,
    sensitivity, optimize and verify)."""
    case = block()
    assert lsmbs.simulate(case, out_dir=tmp_path / "sim").status == "complete"
    assert (tmp_path / "sim" / "summary.json").exists()
    assert lsmbs.sensitivity(case, out_dir=tmp_path / "sens").status == "complete"
    assert (tmp_path / "sens" / "gradients.csv").exists()
