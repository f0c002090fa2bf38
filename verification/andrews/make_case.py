#!/usr/bin/env python3
"""Generates data/andrews/andrews_squeezer.json (Andrews' squeezing mechanism) from the
parameters and consistent initial angles of the IVP test set problem "andrews"
(Mazzia & Magherini, Bari; andrews.F rev. 1.2 2006/10/02, as shipped in the R package
deTestSet, src/Ex_andrews.f, github.com/cran/deTestSet commit d5c4cbe). See data/andrews/README.md
for the mapping between the benchmark's angles and the lsmbs bodies.

Usage: python3 verification/andrews/make_case.py [OUT.json]
"""
import json
import math
import os
import sys

# --- benchmark data (andrews.f, subroutine andfunc / andpar and INIT) -------------------------
P = dict(m1=.04325, m2=.00365, m3=.02373, m4=.00706, m5=.07050, m6=.00706, m7=.05498,
         xa=-.06934, ya=-.00227, xb=-0.03635, yb=.03273, xc=.014, yc=.072, c0=4530.0,
         i1=2.194e-6, i2=4.410e-7, i3=5.255e-6, i4=5.667e-7, i5=1.169e-5, i6=5.667e-7, i7=1.912e-5,
         d=28e-3, da=115e-4, e=2e-2, ea=1421e-5, rr=7e-3, ra=92e-5, l0=7785e-5,
         ss=35e-3, sa=1874e-5, sb=1043e-5, sc=18e-3, sd=2e-2, ta=2308e-5, tb=916e-5,
         u=4e-2, ua=1228e-5, ub=449e-5, zf=2e-2, zt=4e-2, fa=1421e-5, mom=33e-3)
# consistent initial angles beta, Theta, gamma, Phi, delta, Omega, epsilon (velocities 0)
Y0 = [-0.0617138900142764496358948458001, 0.0, 0.455279819163070380255912382449,
      0.222668390165885884674473185609, 0.487364979543842550225598953530,
      -0.222668390165885884674473185609, 1.23054744454982119249735015568]


def rot(a, v):
    c, s = math.cos(a), math.sin(a)
    return [c * v[0] - s * v[1], s * v[0] + c * v[1]]


def add(a, b):
    return [a[0] + b[0], a[1] + b[1]]


def build():
    p = P
    be, th, ga, ph, de, om, ep = Y0
    A, B, C, O = [p["xa"], p["ya"]], [p["xb"], p["yb"]], [p["xc"], p["yc"]], [0.0, 0.0]
    # absolute body angles (lsmbs theta) at t = 0
    t1, t2, t3, t4, t5, t6, t7 = be, be + th, ga, ph + de, de, om + ep, ep
    # body-frame points (body frame = frame rotated by the body's absolute angle)
    F1 = [p["rr"], 0.0]              # crank pin F on body 1 (reference point O)
    E2 = [-p["d"], 0.0]              # E on body 2 (reference point F)
    E3 = [0.0, -p["ss"]]             # E on body 3 (reference point B)
    D3 = [p["sd"], -p["sc"]]         # spring point D on body 3
    G5 = [p["zt"], 0.0]              # G on body 5 (reference point A)
    E4 = [0.0, -p["e"]]              # E on body 4 (reference point G)
    H7 = [0.0, -p["u"]]              # H on body 7 (reference point A)
    E6 = [p["zf"], 0.0]              # E on body 6 (reference point H)
    F = add(O, rot(t1, F1))
    G = add(A, rot(t5, G5))
    H = add(A, rot(t7, H7))
    # consistency check of the initial angles: the four images of E coincide
    Es = [add(F, rot(t2, E2)), add(B, rot(t3, E3)), add(G, rot(t4, E4)), add(H, rot(t6, E6))]
    gap = max(abs(Es[i][k] - Es[0][k]) for i in range(4) for k in range(2))
    assert gap < 1e-15, gap
    Dp = add(B, rot(t3, D3))
    l_init = math.hypot(Dp[0] - C[0], Dp[1] - C[1])

    def rigid(name, pos, ang, m, I, com, comment):
        return {"name": name, "comment": comment, "type": "rigid", "position": pos, "angle": ang,
                "mass": m, "inertia": I, "com": com}

    bodies = [
        rigid("K1", O, t1, p["m1"], p["i1"], [p["ra"], 0.0],
              "crank O-F; reference point O; theta = beta; com at ra from O (direction immaterial: pinned to ground, no gravity)"),
        rigid("K2", F, t2, p["m2"], p["i2"], [-p["da"], 0.0],
              "rod F-E; reference point F; theta = beta + Theta; E at (-d, 0), com at (-da, 0)"),
        rigid("K3", B, t3, p["m3"], p["i3"], [p["sb"], -p["sa"]],
              "triangle B-E-D; reference point B; theta = gamma; E at (0, -ss), D at (sd, -sc); com at distance sqrt(sa^2+sb^2) from B (direction immaterial)"),
        rigid("K4", G, t4, p["m4"], p["i4"], [0.0, -(p["e"] - p["ea"])],
              "link G-E; reference point G; theta = Phi + delta; E at (0, -e), com at (0, -(e - ea))"),
        rigid("K5", A, t5, p["m5"], p["i5"], [p["ta"], -p["tb"]],
              "body A-G; reference point A; theta = delta; G at (zt, 0); com at distance sqrt(ta^2+tb^2) from A (direction immaterial)"),
        rigid("K6", H, t6, p["m6"], p["i6"], [p["zf"] - p["fa"], 0.0],
              "link H-E; reference point H; theta = Omega + epsilon; E at (zf, 0), com at (zf - fa, 0)"),
        rigid("K7", A, t7, p["m7"], p["i7"], [p["ua"], -p["ub"]],
              "body A-H; reference point A; theta = epsilon; H at (0, -u); com at distance sqrt(ua^2+ub^2) from A (direction immaterial)"),
    ]

    def pt(body, at):
        return {"body": body, "at": at}

    joints = [
        {"name": "O", "type": "revolute", "a": pt("K1", [0.0, 0.0]), "b": {"ground": O}},
        {"name": "B", "type": "revolute", "a": pt("K3", [0.0, 0.0]), "b": {"ground": B}},
        {"name": "A5", "type": "revolute", "a": pt("K5", [0.0, 0.0]), "b": {"ground": A}},
        {"name": "A7", "type": "revolute", "a": pt("K7", [0.0, 0.0]), "b": {"ground": A}},
        {"name": "F", "type": "revolute", "a": pt("K1", F1), "b": pt("K2", [0.0, 0.0])},
        {"name": "G", "type": "revolute", "a": pt("K5", G5), "b": pt("K4", [0.0, 0.0])},
        {"name": "H", "type": "revolute", "a": pt("K7", H7), "b": pt("K6", [0.0, 0.0])},
        {"name": "E23", "type": "revolute", "a": pt("K2", E2), "b": pt("K3", E3)},
        {"name": "E24", "type": "revolute", "a": pt("K2", E2), "b": pt("K4", E4)},
        {"name": "E26", "type": "revolute", "a": pt("K2", E2), "b": pt("K6", E6)},
    ]
    forces = [
        {"name": "spring", "type": "spring_damper", "a": pt("K3", D3), "b": {"ground": C},
         "stiffness": p["c0"], "damping": 0.0, "free_length": p["l0"],
         "comment": "c0 = 4530 N/m, l0 = 0.07785 m, between D on K3 and the ground point C (initial length %.6f m)" % l_init},
        {"name": "drive", "type": "torque", "body": "K1", "torque": p["mom"], "scale": 1.0,
         "comment": "mom = 0.033 N m on the crank"},
    ]
    measures = []
    for i in range(1, 8):
        measures.append({"name": "th%d" % i, "type": "angle", "body": "K%d" % i})
    for i in range(1, 8):
        measures.append({"name": "w%d" % i, "type": "angular_velocity", "body": "K%d" % i})
    measures += [
        {"name": "E", "type": "position", "point": pt("K2", E2)},
        {"name": "spring_length", "type": "distance", "a": pt("K3", D3), "b": {"ground": C}},
        {"name": "energy", "type": "kinetic_energy"},
    ]
    responses = [
        {"name": "final_beta", "measure": "th1", "aggregate": "final"},
        {"name": "mean_gamma", "measure": "th3", "aggregate": "average"},
        {"name": "mean_beta", "measure": "th1", "aggregate": "average"},
        {"name": "energy_integral", "measure": "energy", "aggregate": "integral"},
        {"name": "gamma_integral", "measure": "th3", "aggregate": "integral"},
    ]
    design = {
        "variables": [
            {"name": "k", "initial": p["c0"], "lower": 3000.0, "upper": 6000.0},
            {"name": "tq", "initial": 1.0, "lower": 0.5, "upper": 1.5},
            {"name": "m3", "initial": p["m3"], "lower": 0.015, "upper": 0.035},
        ],
        "parameters": [
            {"parameter": "spring.stiffness", "variable": "k"},
            {"parameter": "drive.scale", "variable": "tq"},
            {"parameter": "K3.mass", "variable": "m3"},
        ],
    }
    return {
        "name": "andrews_squeezer",
        "description": "Andrews' squeezing mechanism (seven-body mechanism, Hairer & Wanner II, sec. VII.7; "
                       "IVP test set problem 'andrews'): 7 rigid bodies, 10 revolute joints, a spring "
                       "D-C and a constant torque on the crank; no gravity; t in [0, 0.03] s. "
                       "Generated by verification/andrews/make_case.py; see data/andrews/README.md.",
        "gravity": [0.0, 0.0],
        "bodies": bodies,
        "joints": joints,
        "forces": forces,
        "simulation": {"t_end": 0.03, "h": 1e-5, "rho_inf": 0.8, "tol_r": 1e-12},
        "output": {"csv_stride": 1, "vtu_stride": 1000000, "measures": measures, "responses": responses},
        "design": design,
    }


if __name__ == "__main__":
    here = os.path.dirname(os.path.abspath(__file__))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "..", "data", "andrews", "andrews_squeezer.json")
    with open(out, "w") as f:
        json.dump(build(), f, indent=1)
        f.write("\n")
    print("wrote", os.path.normpath(out))
