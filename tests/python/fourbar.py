"""A crank-rocker four-bar with a flexible steel coupler, for the VTK output tests, and its
closed-form position analysis (the reference the written files are compared with).

Ground pivots O2 = (0, 0) and O4 = (D, 0); crank O2A of length R2 driven through the ramp law
θ2(t) = W t² / (2 TR) for t ≤ TR, W (t − TR/2) afterwards; coupler AB of length L3 (a 30 × 2 quad
plate pinned at the mid-nodes of its short sides); rocker O4B of length R4. Grashof:
R2 + L3 = 0.20 < R4 + D = 0.22, so the crank turns fully."""
import math

import numpy as np

import lsmbs
from lsmbs import at, nearest, rectangle

R2, L3, R4, D = 0.05, 0.15, 0.10, 0.12  # [m]
WIDTH, NX, NY = 0.01, 30, 2              # coupler plate: width [m], elements
W, TR = 2 * math.pi, 0.1                 # crank speed [rad/s] after the ramp of TR [s]


def crank_angle(t):
    return W * t * t / (2 * TR) if t <= TR else W * (t - TR / 2)


def joints(theta2):
    """Closed-form positions of A and B at crank angle θ2 (the assembly with B above the line
    A O4): B is the intersection of the circles |B − A| = L3 and |B − O4| = R4."""
    a = np.array([R2 * math.cos(theta2), R2 * math.sin(theta2)])
    o4 = np.array([D, 0.0])
    d = np.linalg.norm(o4 - a)
    x = (L3 ** 2 - R4 ** 2 + d ** 2) / (2 * d)  # along A→O4 from A
    y = math.sqrt(L3 ** 2 - x ** 2)
    u = (o4 - a) / d
    n = np.array([-u[1], u[0]])
    return a, a + x * u + y * n


def build(vtu_stride=25, t_end=0.5, h=0.005):
    a, b = joints(0.0)
    coupler_angle = math.atan2(b[1] - a[1], b[0] - a[0])
    rocker_angle = math.atan2(b[1], b[0] - D)
    m = lsmbs.ModelBuilder("fourbar_flexible_coupler")
    # centres of mass on the link lines: they are collinear with the pins (the outline stays a line)
    m.rigid_body("crank", mass=0.2, inertia=2e-4, com=(R2 / 2, 0))
    m.rigid_body("rocker", position=(D, 0), angle=rocker_angle, mass=0.3, inertia=5e-4,
                 com=(R4 / 2, 0))
    m.flexible_body("coupler", rectangle((0, -WIDTH / 2), (L3, WIDTH), (NX, NY)), E=210e9,
                    nu=0.3, rho=7800, thickness=0.01, origin=tuple(a), angle=coupler_angle)
    m.revolute("o2", at("crank"))
    m.revolute("o4", at("rocker"))
    m.revolute("pa", nearest("coupler", (0, 0)), at("crank", (R2, 0)))
    m.revolute("pb", nearest("coupler", (L3, 0)), at("rocker", (R4, 0)))
    m.rotation_driver("drive", "crank", lsmbs.ramp(W, TR))
    m.measure("pin_b", "position", point=at("rocker", (R4, 0)))
    m.output(vtu_stride=vtu_stride)
    m.simulation(t_end=t_end, h=h)
    return m, coupler_angle


def reference_mesh(coupler_angle):
    """The coupler's nodes at t = 0: the rectangle's grid placed at A(0) turned by the coupler's
    initial angle (in no particular order)."""
    a, _ = joints(0.0)
    xs, ys = np.meshgrid(np.linspace(0, L3, NX + 1), np.linspace(-WIDTH / 2, WIDTH / 2, NY + 1))
    X = np.column_stack([xs.ravel(), ys.ravel()])
    c, s = math.cos(coupler_angle), math.sin(coupler_angle)
    return a + X @ np.array([[c, -s], [s, c]]).T
