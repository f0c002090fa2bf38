#!/usr/bin/env python3
"""The fixed-mesh mapping against body-fitted meshes, on the optima of paper_results: each
optimum is simulated on its fixed mesh at two resolutions (lsmbs simulate with the design set),
exported (scripts/export_design.py's lsmbs.export) and simulated on a body-fitted Gmsh mesh of the
component at half the finer fixed mesh's element size, the reference. Mass and the constrained
response of each; written to paper_results/body_fitted/table.md and results.json.

    python3 paper_results/body_fitted/make_body_fitted.py --lsmbs build/src/lsmbs [--only arm]

Cases (design from the run's summary.json):
  arm   robot_arm_mma (robot_arm_holes.json): plate 120 × 10 and 240 × 20 quadrilaterals
        (h = 5 and 2.5 mm); average_tip_deviation
  rod1  slider_crank_1hole (rod.msh) and slider_crank_1hole_coarse (rod_coarse.msh) at the
        fine run's optimum; elongation
  rod3  slider_crank_3holes and slider_crank_3holes_coarse at the fine run's optimum; elongation
  arm_length_scale  the best start of robot_arm_length_scale (the multi-start with the length-scale
        constraints), as arm
  arm_robust  robot_arm_robust (the robust formulation's optimum), as arm; the nominal design
  arm3d robot_arm_3d_mma (data/spatial/robot_arm_holes_3d.json, the plate a 3D solid optimized
        on 60 × 5 × 1 bricks): fixed meshes of 60 × 5 × 1 and 120 × 10 × 1 bricks against one
        layer of body-fitted hexahedra of h = 2.5 mm; also writes the optimum's STEP file into
        the run's final_design/
  arm3d_ls  robot_arm_3d_length_scale (the same with length-scale constraints of 10 mm), as
        arm3d
"""
import argparse
import importlib.util
import json
import pathlib
import subprocess
import sys
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent.parent


def load_export():
    spec = importlib.util.spec_from_file_location("lsmbs_export", ROOT / "python/lsmbs/export.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


CASES = {
    "arm": {"run": "robot_arm_mma", "body": "plate", "mass": "plate_mass",
            "response": "average_tip_deviation",
            "fixed": [("data/robot_arm/robot_arm_holes.json", [], "120 × 10 quads, h = 5 mm"),
                      ("data/robot_arm/robot_arm_holes.json",
                       ["/bodies/2/mesh/elements=[240,20]"], "240 × 20 quads, h = 2.5 mm")]},
    "arm_length_scale": {"run": "robot_arm_length_scale", "body": "plate", "mass": "plate_mass",
                         "response": "average_tip_deviation", "fixed": "arm"},
    "arm_robust": {"run": "robot_arm_robust", "body": "plate", "mass": "plate_mass",
                   "response": "average_tip_deviation", "fixed": "arm"},
    # the worked 3D example: the plate a solid of one brick through its 2.5 mm thickness,
    # optimized on 60 x 5 x 1 bricks; its body-fitted mesh is the optimum's section meshed by
    # quadrilaterals and extruded into one layer of hexahedra (lsmbs.export.write_msh_solid)
    "arm3d": {"run": "robot_arm_3d_mma", "body": "plate", "mass": "plate_mass",
              "response": "average_tip_deviation", "h": 0.0025, "layers": 1,
              "fixed": [("data/spatial/robot_arm_holes_3d.json",
                         ["/bodies/2/mesh/elements=[60,5,1]"], "60 × 5 × 1 bricks, h = 10 mm"),
                        ("data/spatial/robot_arm_holes_3d.json", [],
                         "120 × 10 × 1 bricks, h = 5 mm")]},
    # the same with length-scale control (min_size 10 mm, one brick): robot_arm_3d_length_scale
    "arm3d_ls": {"run": "robot_arm_3d_length_scale", "body": "plate", "mass": "plate_mass",
                 "response": "average_tip_deviation", "h": 0.0025, "layers": 1,
                 "fixed": "arm3d"},
    "rod1": {"run": "slider_crank_1hole", "body": "rod", "mass": "rod_mass",
             "response": "max_elongation",
             "fixed": [("data/slider_crank/slider_crank_1hole_coarse.json", [], "rod_coarse.msh"),
                       ("data/slider_crank/slider_crank_1hole.json", [], "rod.msh")]},
    "rod3": {"run": "slider_crank_3holes", "body": "rod", "mass": "rod_mass",
             "response": "max_elongation",
             "fixed": [("data/slider_crank/slider_crank_3holes_coarse.json", [], "rod_coarse.msh"),
                       ("data/slider_crank/slider_crank_3holes.json", [], "rod.msh")]},
}


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("make_body_fitted: %s failed (%d): %s" % (" ".join(map(str, cmd)), p.returncode,
                                                          p.stderr.strip()[-400:]))
    return p


def responses(out):
    S = json.loads((out / "summary.json").read_text())
    return S["responses"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lsmbs", required=True)
    ap.add_argument("--only", default=None, help="one of " + ", ".join(CASES))
    ap.add_argument("--work", default=None, help="scratch folder (default: a temporary one)")
    a = ap.parse_args()
    lsmbs = str(pathlib.Path(a.lsmbs).resolve())
    work = pathlib.Path(a.work or tempfile.mkdtemp(prefix="lsmbs_body_fitted_"))
    ex = load_export()
    results = {}
    for key, c in CASES.items():
        if a.only and key != a.only:
            continue
        if isinstance(c["fixed"], str):
            c = {**c, "fixed": CASES[c["fixed"]]["fixed"]}
        folder = HERE.parent / c["run"]
        S = json.loads((folder / "summary.json").read_text())
        if "ranking" in S:  # a multi-start: its best start
            folder = folder / ("start_%d" % S["ranking"]["best_start"])
            S = json.loads((folder / "summary.json").read_text())
        design = S["final"]["design"]
        sets = ["%s=%.17g" % kv for kv in sorted(design.items())]
        rows = []
        shape = None
        for k, (case, extra, label) in enumerate(c["fixed"]):
            out = work / ("%s_fixed%d" % (key, k))
            overrides = [x for s in sets + extra for x in ("--set", s)]
            run([lsmbs, "simulate", str(ROOT / case), "-o", str(out), "-q", "--overwrite",
                 "--set", "/output/vtu_stride=0", *overrides])
            r = responses(out)
            rows.append({"model": "fixed mesh, " + label, "mass": r[c["mass"]],
                         "response": r[c["response"]]})
            geo = work / ("%s_geometry%d" % (key, k))
            run([lsmbs, "geometry", str(ROOT / case), "-o", str(geo), "--overwrite", *overrides])
            shape = json.loads((geo / (c["body"] + "_shape.json")).read_text())
            fine_case = ROOT / case
        cad = work / (key + "_cad")
        if shape.get("kind") == "solid":
            h = c["h"]
            cad.mkdir(parents=True, exist_ok=True)
            msh, sets_found = ex.write_msh_solid(shape, cad / "plate.msh", h, c["layers"])
            files = {"msh": msh, "node_sets": sets_found}
            ex.export(shape, folder / "final_design", ("step", "png"))  # CAD and a section
        else:
            h = shape["element_size"] / 2
            files = ex.export(shape, cad, ("msh",), size=h)
        missing = [n for n, cv in files["node_sets"].items() if not cv]
        bf = ex.body_fitted_case(fine_case, c["body"], files["msh"], cad / "body_fitted.json")
        doc = json.loads(pathlib.Path(bf).read_text())
        doc.setdefault("output", {})["vtu_stride"] = 0
        pathlib.Path(bf).write_text(json.dumps(doc))
        out = work / (key + "_body_fitted")
        run([lsmbs, "simulate", bf, "-o", str(out), "-q", "--overwrite"])
        r = responses(out)
        nodes = sum(1 for _ in open(files["msh"]))  # size of the file, for the record
        label = "body-fitted, h = %.3g mm (Gmsh)" % (h * 1e3)
        if shape.get("kind") == "solid":
            label = "body-fitted hexahedra, h = %.3g mm, %d layer (Gmsh)" % (h * 1e3, c["layers"])
        rows.append({"model": label, "mass": r[c["mass"]],
                     "response": r[c["response"]], "msh_lines": nodes,
                     "node_sets_not_on_the_boundary": missing})
        ref = rows[-1]
        for row in rows:
            row["mass_error"] = row["mass"] / ref["mass"] - 1
            row["response_error"] = row["response"] / ref["response"] - 1
        results[key] = {"run": str(folder.relative_to(HERE.parent)), "design": design, "response": c["response"], "rows": rows}
        print(key, json.dumps(rows, indent=1))
    if a.only:
        prev = HERE / "results.json"
        if prev.exists():
            results = {**json.loads(prev.read_text()), **results}
    (HERE / "results.json").write_text(json.dumps(results, indent=1))
    lines = ["# Fixed mesh against body-fitted (generated by make_body_fitted.py)", ""]
    for key, R in results.items():
        lines += ["## %s (%s), %s" % (key, R["run"], R["response"]), "",
                  "| model | mass [g] | vs body-fitted | %s | vs body-fitted |" % R["response"],
                  "|---|---|---|---|---|"]
        for row in R["rows"]:
            lines.append("| %s | %.4f | %+.2f %% | %.6g | %+.2f %% |" % (
                row["model"], row["mass"] * 1e3, 100 * row["mass_error"], row["response"],
                100 * row["response_error"]))
        lines.append("")
    (HERE / "table.md").write_text("\n".join(lines))
    print("written", HERE / "table.md")


if __name__ == "__main__":
    main()
