"""Pictures read back pixel by pixel (Pillow) against closed forms: the time-history plot of
`simulate` (a crank turned at a known angle law: its pin's x(t) is r cos θ(t))."""
import math

import numpy as np
import pytest
from PIL import Image

import lsmbs
from lsmbs import at

from conftest import run_cli

R, W, TR = 0.2, 2 * math.pi, 0.1  # crank [m]; speed [rad/s] after a ramp of TR [s]


def theta(t):
    return W * t * t / (2 * TR) if t <= TR else W * (t - TR / 2)


def frames(img):
    """The plot frame of a picture: the first and last long dark vertical lines (left, right) and
    the rows of the long dark horizontal lines (borders: top and bottom of each panel)."""
    dark = np.all(img < 80, axis=2)
    rows = [y for y in range(dark.shape[0]) if dark[y].sum() > 0.5 * dark.shape[1]]
    # vertical borders: columns dark over most of the rows between the first and last border row
    span = slice(rows[0], rows[-1] + 1)
    cols = [x for x in range(dark.shape[1]) if dark[span, x].sum() > 0.5 * (rows[-1] - rows[0])]
    return cols[0], cols[-1], rows


def test_the_history_plot_follows_the_closed_form_on_its_axes(tmp_path):
    m = lsmbs.ModelBuilder("crank")
    m.rigid_body("crank", mass=1, inertia=0.01)
    m.revolute("pivot", at("crank"))
    m.rotation_driver("drive", "crank", lsmbs.ramp(W, TR))
    m.measure("pin", "position", point=at("crank", (R, 0)))
    m.simulation(t_end=1.05, h=0.005)  # θ(1.05) = 2π: both ±R reached on grid points
    m.save(tmp_path / "crank.json")
    S = run_cli("simulate", tmp_path / "crank.json", "-o", tmp_path / "out")
    assert "history.png" in S["files"]
    img = np.asarray(Image.open(tmp_path / "out" / "history.png").convert("RGB")).astype(int)
    assert img.shape == (40 + 64 + 200, 900, 3)  # one panel (io/plot.hpp's layout)
    left, right, rows = frames(img)
    top, bottom = rows[0], rows[-1]
    assert right - left > 500 and bottom - top > 150
    # y range: [−R, R] widened by 5 % of 2R on both sides; x range: [0, t_end]
    lo, hi = -1.1 * R, 1.1 * R
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    blue = (b - r > 60) & (b > 120) & (g < b)  # the first series (#1f77b4), anti-aliased
    checked, worst = 0, 0.0
    for px in range(left + 2, right - 1):
        ys = np.where(blue[top + 1:bottom, px])[0] + top + 1
        if len(ys) == 0:
            continue
        t = (px - left) / (right - left) * 1.05
        y_exact = bottom - (R * math.cos(theta(t)) - lo) / (hi - lo) * (bottom - top)
        worst = max(worst, abs(ys.mean() - y_exact) - (ys.max() - ys.min()) / 2)
        checked += 1
    assert checked > 0.9 * (right - left - 3)
    assert worst < 2.0, worst  # pixels (measured 0.95; with the y range off by the 5 % padding: 9)
