"""Pictures read back pixel by pixel (Pillow) against closed forms: the time-history plot of
`simulate` (a crank turned at a known angle law: its pin's x(t) is r cos θ(t)), and the design
picture of `geometry` (a circular hole: its red zero contour on the circle, the axis ticks at round
millimetres, the colour bar's grey levels back to the μ_e of the design VTU). The pixel ↔ body
mapping is found in each picture (the plate's black region), not taken from the code."""
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


def design_picture(tmp_path):
    """A 0.2 × 0.1 m plate with a circular hole of radius 0.03 m at (0.1, 0.05): `lsmbs geometry`
    draws it; returns the RGB pixels and the μ_e of the design VTU."""
    from test_vtu import read_vtu
    from lsmbs import circle, rectangle
    m = lsmbs.ModelBuilder("plate")
    m.flexible_body("plate", rectangle((0, 0), (0.2, 0.1), (40, 20)), E=70e9, nu=0.3, rho=2700,
                    thickness=0.001)
    m.clamp("c", "plate", "left")
    r = m.variable("r", 0.03, 0.01, 0.04)
    m.features("plate", [circle("h", 0.1, 0.05, r)])
    m.simulation(t_end=0.01, h=0.01)
    m.save(tmp_path / "plate.json")
    S = run_cli("geometry", tmp_path / "plate.json", "-o", tmp_path / "geo", "--width", 800)
    assert "plate.png" in S["files"]
    img = np.asarray(Image.open(tmp_path / "geo" / "plate.png").convert("RGB")).astype(int)
    pts, arrays = read_vtu(tmp_path / "geo" / "plate.vtu")
    return img, pts, arrays["mu"]


def black_runs(line):
    """Longest run of black pixels along a line of RGB pixels: (length, first index)."""
    best, start, run = (0, 0), 0, 0
    for k, black in enumerate(np.all(line == 0, axis=1)):
        run = run + 1 if black else 0
        if run == 1:
            start = k
        best = max(best, (run, start))
    return best


def plate_mapping(img):
    """Pixel ↔ body frame from the picture alone: the largest connected black region is the plate
    [0, 0.2] × [0, 0.1] m (μ = 1 around the hole); its bounding box gives the scale. Also returns
    the rows and columns of the drawing's frame: the black lines around that box."""
    from scipy import ndimage
    labels, n = ndimage.label(np.all(img == 0, axis=2))
    sizes = ndimage.sum(np.ones_like(labels), labels, range(1, n + 1))
    ys, xs = np.where(labels == 1 + int(np.argmax(sizes)))
    x0, x1, y0, y1 = xs.min(), xs.max() + 1, ys.min(), ys.max() + 1  # pixel edges
    sx, sy = (x1 - x0) / 0.2, (y1 - y0) / 0.1  # pixels per metre

    def body(px, py):  # of pixel centres
        return (px + 0.5 - x0) / sx, (y1 - py - 0.5) / sy
    mid_x, mid_y = (x0 + x1) // 2, (y0 + y1) // 2
    left = max(c for c in range(x0) if np.all(img[mid_y, c] == 0))
    right = min(c for c in range(x1, img.shape[1]) if np.all(img[mid_y, c] == 0))
    top = max(r for r in range(y0) if np.all(img[r, mid_x] == 0))
    bottom = min(r for r in range(y1, img.shape[0]) if np.all(img[r, mid_x] == 0))
    return (left, right, top, bottom), body, sx, sy


def test_the_design_picture_draws_the_hole_boundary_on_the_circle(tmp_path):
    img, _, _ = design_picture(tmp_path)
    (left, right, top, bottom), body, sx, sy = plate_mapping(img)
    assert sx == pytest.approx(sy, rel=0.01)  # one scale in x and y
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    red = (r > 150) & (g < 80) & (b < 80)
    red[:, right:] = False  # the contour's key under the colour bar
    ys, xs = np.where(red)
    X, Y = body(xs, ys)
    d = np.hypot(X - 0.1, Y - 0.05) - 0.03
    assert len(d) > 300
    # within one pixel of the circle (plus the half pixel between a pixel's centre and the line)
    # measured 1.16 px: up to √2/2 from a pixel's centre to the point of the line inside it,
    # 0.3 px of chord error of the linear crossings (h²/8r with h = 5 mm, r = 30 mm)
    assert np.max(np.abs(d)) * sx < 1.5, np.max(np.abs(d)) * sx
    angles = np.degrees(np.arctan2(Y - 0.05, X - 0.1))
    assert len(np.unique(np.floor(angles / 10))) == 36  # all the way round


def test_the_design_picture_axes_tick_at_round_millimetres(tmp_path):
    img, _, _ = design_picture(tmp_path)
    (left, right, top, bottom), body, sx, _ = plate_mapping(img)
    row = np.all(img[bottom + 3] < 80, axis=1)  # the tick marks below the frame
    cols = np.where(row[left - 1:right + 1])[0] + left - 1
    mm = np.array([body(c, 0)[0] * 1e3 for c in cols])
    step = np.diff(mm)
    px_mm = 1e3 / sx
    assert len(mm) >= 4 and np.ptp(step) < 2 * px_mm
    nice = min((m * 10.0 ** k for m in (1, 2, 5) for k in range(-2, 4)),
               key=lambda s: abs(s - step.mean()))
    assert abs(step.mean() - nice) < px_mm
    assert np.max(np.abs(mm / nice - np.round(mm / nice))) * nice < 1.5 * px_mm
    assert np.any(np.abs(mm) < 1.5 * px_mm)  # a tick at x = 0


def test_the_colour_bar_maps_grey_levels_back_to_mu_monotonically(tmp_path):
    img, pts, mu = design_picture(tmp_path)
    (left, right, top, bottom), body, sx, sy = plate_mapping(img)
    # the bar's frame: the last two columns holding a long vertical black line
    lines = [c for c in range(right + 1, img.shape[1]) if black_runs(img[:, c])[0] >= 150]
    bl, br = lines[-2], lines[-1]
    run, start = black_runs(img[:, bl])
    bar = img[start + 1:start + run - 1, (bl + br) // 2]  # inside the frame, top to bottom
    assert np.all(bar[:, 0] == bar[:, 1]) and np.all(bar[:, 1] == bar[:, 2])  # greys
    bar = bar[:, 0]
    assert np.all(np.diff(bar) >= 0)  # monotonic: darker (more material) upwards
    assert bar[0] <= 2 and bar[-1] >= 253 and len(bar) >= 150
    # cut elements (0.05 < μ_e < 0.95) of the 40 × 20 grid: the bar row with the grey of the
    # pixel at the element's centre sits at μ_e (μ_min = 1e-3 by default)
    mu_min, worst, n = 1e-3, 0.0, 0
    neutral = (img[..., 0] == img[..., 1]) & (img[..., 1] == img[..., 2])
    for e in np.where((mu > 0.05) & (mu < 0.95))[0]:
        cx, cy = (e % 40 + 0.5) * 0.005, (e // 40 + 0.5) * 0.005
        # the pixel whose centre is nearest the element's centre (body() inverted)
        px = int(round(cx * sx + body(0, 0)[0] * -sx))
        py = int(round(-cy * sy - body(0, 0)[1] * -sy))
        assert abs(body(px, py)[0] - cx) <= 0.5 / sx + 1e-12
        if not neutral[py, px]:
            continue  # under the contour
        k = np.argmin(np.abs(bar - img[py, px, 0]))
        mu_bar = 1 - (k + 0.5) / len(bar) * (1 - mu_min)
        worst = max(worst, abs(mu_bar - mu[e]))
        n += 1
    assert n >= 10
    # a grey level is 1/255 of the range, a bar row 1/len(bar): measured 0.0027
    assert worst < 0.01, worst


def test_sensitivity_with_several_methods_draws_their_derivatives_side_by_side(tmp_path):
    """The oscillator of test_builder.py: x(t) = L0 + A cos(√(k/m) t); ∂x(T)/∂k > 0 at T = 1 s and
    the mean's derivative < 0 (closed forms there). Three methods agree to 1e-6, so their bars,
    each divided by the first method's magnitude, are ±1: the same height, on the closed form's side
    of zero."""
    from test_builder import A, K0, M, T_END, oscillator
    w = math.sqrt(K0 / M)
    assert -A * math.sin(w * T_END) * T_END / (2 * math.sqrt(K0 * M)) > 0  # ∂x(T)/∂k
    oscillator().save(tmp_path / "osc.json")
    methods = ["direct-analytic", "fd-central", "semi-analytical"]
    S = run_cli("sensitivity", tmp_path / "osc.json", "--method", ",".join(methods),
                "-o", tmp_path / "out")
    assert {"methods.csv", "methods.png", "gradients.csv"} <= set(S["files"])
    assert list(S["methods"]) == methods
    g = [S["methods"][m]["gradients"]["x_end"]["k"] for m in methods]
    assert g[0] == S["gradients"]["x_end"]["k"]  # the first method's are the gradients
    assert max(abs(x / g[0] - 1) for x in g) < 1e-6
    img = np.asarray(Image.open(tmp_path / "out" / "methods.png").convert("RGB")).astype(int)
    assert img.shape == (560, 900, 3)
    left, right, rows = frames(img)
    colours = [(0x1f, 0x77, 0xb4), (0xd6, 0x27, 0x28), (0x2c, 0xa0, 0x2c)]  # io/plot.hpp
    # the zero line: the long dark row strictly inside the frame
    zero = [r for r in rows if rows[0] + 2 < r < rows[-1] - 2]
    assert len(zero) >= 1
    zero = zero[0]
    tops, bottoms = [], []
    for c in colours:
        mask = np.all(np.abs(img - c) <= 40, axis=2)
        mask[:, right:] = False  # the key
        ys, xs = np.where(mask)
        first = xs < xs.min() + (xs.max() - xs.min()) / 2  # x_end's group, then x_mean's
        tops.append(ys[first].min())
        assert ys[first].max() < zero  # x_end: ∂/∂k > 0, above zero
        bottoms.append(ys[~first].max())
        assert ys[~first].min() > zero  # x_mean: below zero
    assert np.ptp(tops) <= 1 and np.ptp(bottoms) <= 1
    # +1 on the axis: the y range is [−1, 1] widened by 10 % of 2 (io/plot.hpp), 1 is 1/2.4 of it
    # above zero
    span = rows[-1] - rows[0]
    assert abs((zero - tops[0]) / span - 1 / 2.4) < 0.01, ((zero - tops[0]) / span)


@pytest.mark.parametrize("methods, says", [("direct-analytic,bogus", "'bogus' is not a method"),
                                           ("fd-central,fd-central", "given twice")])
def test_a_bad_method_list_is_a_usage_error(tmp_path, methods, says):
    import subprocess
    from conftest import CLI
    from test_builder import oscillator
    oscillator().save(tmp_path / "osc.json")
    p = subprocess.run([CLI, "sensitivity", str(tmp_path / "osc.json"), "--method", methods,
                        "-o", str(tmp_path / "out")], capture_output=True, text=True)
    assert p.returncode == 2 and says in p.stderr and "--method" in p.stderr
    assert not (tmp_path / "out").exists()
