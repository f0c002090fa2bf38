#!/usr/bin/env python3
"""Writes the slider-crank case files of this folder (run after changing rod.geo or the model).

slider_crank_1hole.json   - section 5.2: one elliptical hole (eq. 41), Table 1
slider_crank_3holes.json  - section 5.3: three elliptical holes (Table 2), Table 3
*_coarse.json             - the same on rod_coarse.msh (tests, quick looks)
Usage: python3 make_cases.py
"""
import json
import math

R_CRANK, L_ROD = 0.045, 0.1356
OMEGA = 4000 * 2 * math.pi / 60
PISTON_AREA = math.pi * 0.084 ** 2 / 4   # bore 84 mm, see make_pressure.py


def model(name, description, mesh_file):
    big, small = [R_CRANK, 0.0], [R_CRANK + L_ROD, 0.0]
    return {
        "name": name,
        "description": description,
        "gravity": [0, 0],
        "bodies": [
            {"name": "crank", "type": "rigid", "position": [0, 0], "angle": 0, "mass": 2.0, "inertia": 0.002,
             "comment": "balanced crank; its inertia does not affect the driven motion"},
            {"name": "big_end", "type": "rigid", "position": big, "angle": 0, "mass": 0, "inertia": 0,
             "comment": "massless rigid connection of the big-end bore to the crank pin"},
            {"name": "rod", "type": "flexible",
             "mesh": {"type": "gmsh", "file": mesh_file, "scale": 1e-3},
             "placement": {"origin": small, "angle": math.pi},
             "material": {"E": 210e9, "nu": 0.3, "rho": 7800}, "thickness": 0.01,
             "comment": "mesh frame (rod.geo): small-end bore centre at the origin, big end at (135.6, 0) mm"},
            {"name": "small_end", "type": "rigid", "position": small, "angle": 0, "mass": 0, "inertia": 0,
             "comment": "massless rigid connection of the small-end bore to the gudgeon pin"},
            {"name": "piston", "type": "rigid", "position": small, "angle": 0, "mass": 0.456, "inertia": 0},
        ],
        "joints": [
            {"name": "main_bearing", "type": "revolute", "a": {"body": "crank", "at": [0, 0]}, "b": {"ground": [0, 0]}},
            {"name": "crank_pin", "type": "revolute", "a": {"body": "crank", "at": [R_CRANK, 0]},
             "b": {"body": "big_end", "at": [0, 0]}},
            {"name": "big_end_connection", "type": "rigid_connection", "rigid": "big_end", "flexible": "rod",
             "node_set": "bore_big"},
            {"name": "small_end_connection", "type": "rigid_connection", "rigid": "small_end", "flexible": "rod",
             "node_set": "bore_small"},
            {"name": "gudgeon_pin", "type": "revolute", "a": {"body": "small_end", "at": [0, 0]},
             "b": {"body": "piston", "at": [0, 0]}},
            {"name": "cylinder", "type": "prismatic", "a": {"body": "piston", "at": [0, 0]}, "direction": [1, 0],
             "lock_rotation": True},
            {"name": "crank_drive", "type": "rotation_driver", "body": "crank",
             "law": {"type": "ramp", "from": 0, "speed": OMEGA, "ramp_time": 0.01}},
        ],
        "forces": [
            {"name": "gas", "type": "pressure", "point": {"body": "piston", "at": [0, 0]}, "direction": [-1, 0],
             "area": PISTON_AREA,
             "table": {"file": "pressure.csv", "x_scale": math.pi / 180, "interpolation": "linear"},
             "argument": {"angle_of": "crank", "offset": -math.pi},
             "comment": "cycle angle 0 (bottom dead centre, start of compression) at crank angle pi, t = 12.5 ms"},
        ],
        "simulation": {"t_end": 0.0425, "h": 2.5e-4, "rho_inf": 0.8},
        "output": {
            "csv_stride": 1, "vtu_stride": 10,
            "measures": [
                {"name": "elongation", "type": "elongation", "a": {"body": "big_end", "at": [0, 0]},
                 "b": {"body": "small_end", "at": [0, 0]}},
                {"name": "rod_mass", "type": "mass", "body": "rod"},
                {"name": "piston", "type": "position", "point": {"body": "piston", "at": [0, 0]}},
                {"name": "crank_angle", "type": "angle", "body": "crank"},
                {"name": "gudgeon_force", "type": "constraint_force", "joint": "gudgeon_pin"},
            ],
            "responses": [
                {"name": "rod_mass", "measure": "rod_mass", "aggregate": "final"},
                {"name": "max_elongation", "measure": "elongation", "aggregate": "max"},
                {"name": "elongation", "measure": "elongation", "aggregate": "per_step"},
            ],
        },
    }


def design_1hole(case):
    case["design"] = {
        "variables": [{"name": "p", "initial": 0.001, "lower": 0.001, "upper": 0.15}],
        "geometry": [{"body": "rod", "features": [
            {"name": "hole", "type": "ellipse", "cx": 0.0678, "cy": 0, "a": 0.05, "b": 0.3, "d": "p",
             "angle": math.pi / 2}]}],
    }


def design_3holes(case):
    v = lambda n, i, lo, hi: {"name": n, "initial": i, "lower": lo, "upper": hi}
    case["design"] = {
        "variables": [v("p1", 0.01, 0, 0.08), v("p2", 0.015, 0, 0.095), v("p3", 0.0875, 0.0668, 0.0968),
                      v("p4", 0.003, 0, 0.004), v("p5", 0.0493, 0.0418, 0.0718)],
        "geometry": [{"body": "rod", "features": [
            {"name": "LS1", "type": "ellipse", "cx": "p3", "cy": 0, "a": 0.06, "b": 0.3, "d": "p1",
             "angle": math.pi / 2},
            {"name": "LS2", "type": "ellipse", "cx": "p5", "cy": {"variable": "p4", "scale": -1}, "a": 0.045,
             "b": 0.28, "d": "p2", "angle": math.pi / 2},
            {"name": "LS3", "type": "ellipse", "cx": "p5", "cy": "p4", "a": 0.045, "b": 0.28, "d": "p2",
             "angle": math.pi / 2}],
            "region": {"and": ["LS1", "LS2", "LS3"]}}],
    }


def optimization(case, max_evaluations):
    # Svanberg's classic MMA: NLopt's CCSA variants (mma, ccsaq) scale their first step with the
    # gradient, which is tiny at the tiny start hole, and stop on the paper's 0.01 % rule after
    # one or two simulations (paper_results/README.md).
    case["optimization"] = {
        "objective": "rod_mass",
        "constraints": [{"response": "elongation", "upper": 16e-6}],
        "optimizer": "mma-svanberg",
        "sensitivity": {"method": "direct-analytic"},
        "stop": {"relative_objective_change": 1e-4, "relative_constraint_violation": 2.5e-3,
                 "max_evaluations": max_evaluations},
    }


def write(path, case):
    with open(path, "w") as f:
        json.dump(case, f, indent=1)
        f.write("\n")
    print("wrote", path)


if __name__ == "__main__":
    for suffix, mesh, note in [("", "rod.msh", ""), ("_coarse", "rod_coarse.msh", " Coarse mesh (tests).")]:
        c = model("slider_crank_1hole" + suffix,
                  "Slider-crank of Tromme et al. section 5.2: reconstructed steel connecting rod (README.md), "
                  "diesel-like gas pressure (make_pressure.py), one elliptical hole (eq. 41) at (67.8, 0) mm "
                  "with its long axis along the rod, p in [0.001, 0.15], start 0.001 (Table 1)." + note, mesh)
        design_1hole(c)
        optimization(c, 30)
        write(f"slider_crank_1hole{suffix}.json", c)
        c = model("slider_crank_3holes" + suffix,
                  "Slider-crank of Tromme et al. section 5.3: three elliptical holes combined by AND (Table 2), "
                  "bounds and initial values of Table 3." + note, mesh)
        design_3holes(c)
        optimization(c, 60)
        write(f"slider_crank_3holes{suffix}.json", c)
