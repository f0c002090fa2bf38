#!/usr/bin/env python3
"""Writes the spatial robot arm of Tromme et al. section 6 whose plate is a 3D solid body
(robot_arm_3d.json, and robot_arm_holes_3d.json with Table 5's initial design) from the planar
cases data/robot_arm/robot_arm.json and robot_arm_holes.json:

    python3 data/spatial/make_robot_arm_3d.py

The mechanism is the planar one turned by -120 degrees about z, so that arm 2 lies along +x at
t = 0 (a solid body's box mesh is axis-aligned in ground coordinates); no gravity acts, so the
turn changes nothing. The 0.6 x 0.05 m plate is a box 2.5 mm thick of 120 x 10 x 1 enhanced
bricks; the massless rods and the 5 kg effector become rigid bodies: arm 1 and the root rod are
driven, so their masses (1 and 0.1 kg) move nothing but the motors; the effector is a 5 kg body
at the rod's end with moments of 1e-6 kg m^2 (the planar point mass has none). Each hole is a
through-hole of the planar super-ellipse, its (u, v) frame at the elbow along arm 2, so the
design variables and their values are the planar case's. The tip deviation is the distance of
the effector from the root rod's point 1 m from the elbow: where the driven chain puts the tip
(the planar path_deviation, eq. 45, evaluates the chain by the driver laws, which the joints
follow to the constraint tolerance). tests/python/test_robot_arm_3d.py compares it with the
plane-stress result (docs/methods.md, "The robot arm in 3D").
"""
import json
import math
import pathlib

HERE = pathlib.Path(__file__).resolve().parent
PLANAR = HERE.parent / "robot_arm"
T = 0.0025  # the plate's thickness
S3 = math.sqrt(3) / 2
ELBOW = [0.5, -S3, 0.0]  # arm 1 at -60 degrees after the turn


def law():
    return {"type": "trapezoid", "from": math.pi / 3, "to": math.pi / 2, "acceleration": 1.0,
            "speed": 0.25}


def spatial(planar, name, description):
    d = json.loads((PLANAR / planar).read_text())
    case = {
        "name": name,
        "description": description,
        "dimension": 3,
        "gravity": [0, 0, 0],
        "bodies": [
            {"name": "arm1", "type": "rigid", "mass": 1.0, "inertia": [0.01, 0.01, 0.01],
             "position": [0.25, -S3 / 2, 0]},
            {"name": "rod_root", "type": "rigid", "mass": 0.1, "inertia": [1e-4, 1e-4, 1e-4],
             "position": [ELBOW[0] + 0.1, ELBOW[1], 0]},
            {"name": "plate", "type": "solid",
             "mesh": {"type": "box", "origin": [ELBOW[0] + 0.2, ELBOW[1] - 0.025, -T / 2],
                      "size": [0.6, 0.05, T], "elements": [120, 10, 1]},
             "material": {"E": 7.2e10, "nu": 0.3, "rho": 2700}},
            {"name": "effector", "type": "rigid", "mass": 5.0, "inertia": [1e-6, 1e-6, 1e-6],
             "position": [ELBOW[0] + 1.0, ELBOW[1], 0]}],
        "joints": [
            {"name": "base", "type": "revolute", "a": "ground", "b": "arm1", "at": [0, 0, 0],
             "axis": [0, 0, 1]},
            {"name": "elbow", "type": "revolute", "a": "arm1", "b": "rod_root", "at": ELBOW,
             "axis": [0, 0, 1]},
            {"name": "theta1", "type": "rotation_driver", "joint": "base", "law": law(),
             "offset": math.pi / 3},
            {"name": "theta2", "type": "rotation_driver", "joint": "elbow", "law": law(),
             "offset": math.pi / 3},
            {"name": "root_connection", "type": "solid_connection", "solid": "plate",
             "node_set": "xmin", "body": "rod_root"},
            {"name": "tip_connection", "type": "solid_connection", "solid": "plate",
             "node_set": "xmax", "body": "effector"}],
        "simulation": d["simulation"],
        "output": {
            "measures": [
                {"name": "tip_deviation", "type": "distance",
                 "a": {"body": "rod_root", "at": [ELBOW[0] + 1.0, ELBOW[1], 0]},
                 "b": {"body": "effector"}},
                {"name": "plate_mass", "type": "mass", "body": "plate"}],
            "responses": d["output"]["responses"]},
    }
    if "design" in d:
        design = json.loads(json.dumps(d["design"]))
        for g in design["geometry"]:
            g["features"] = [
                {"name": f["name"], "type": "through_hole", "profile": f["type"],
                 "face": {"origin": [ELBOW[0], ELBOW[1], T / 2], "normal": [0, 0, -1],
                          "u_axis": [1, 0, 0]},
                 **{k: v for k, v in f.items() if k not in ("name", "type")}}
                for f in g["features"]]
        case["design"] = design
        case["optimization"] = d["optimization"]
    return case


def main():
    cases = {
        "robot_arm_3d.json": spatial(
            "robot_arm.json", "robot_arm_3d",
            "The robot arm of Tromme et al. section 6 (data/robot_arm/robot_arm.json) in space: "
            "its plate a 3D solid body 2.5 mm thick (120 x 10 x 1 enhanced bricks) instead of "
            "plane-stress quadrilaterals, no holes. Written by make_robot_arm_3d.py."),
        "robot_arm_holes_3d.json": spatial(
            "robot_arm_holes.json", "robot_arm_holes_3d",
            "The robot arm of Tromme et al. section 6 in space with Table 5's initial design "
            "(data/robot_arm/robot_arm_holes.json): five super-ellipse holes drilled through a "
            "3D plate 2.5 mm thick, the planar case's 15 design variables. Written by "
            "make_robot_arm_3d.py."),
    }
    for name, case in cases.items():
        (HERE / name).write_text(json.dumps(case, indent=1) + "\n")
        print(HERE / name)


if __name__ == "__main__":
    main()
