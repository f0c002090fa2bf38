#!/usr/bin/env python3
"""Structure-aware mutation fuzzer of the lsmbs command line (issue 19).

    structure_fuzz.py --lsmbs BIN [--seed S] [--count N] [--corpus DIR] [--save] [--jobs J] [-v]

Starts from every shipped case (data/**/*.json), the case examples of docs/*.md and a few
generated mechanisms (verification/corpus/gen_mechanisms.py), shortens each run to a few time
steps, applies one to four JSON-aware mutations (delete a key, change a value's type, numbers to
NaN / inf / huge / tiny / negative / zero, empty arrays and objects, duplicated names, renamed
references, swapped enumerants, unit changes, duplicated or unknown keys, truncated text, huge
arrays, deep nesting, file references to folders, devices and wrong files, --set values) and runs
`lsmbs simulate` (or, less often, `sensitivity` or `optimize --no-check`) on the result in a fresh
output folder. Every run must keep the promise of docs/case-format.md:

  * the process ends with exit code 0, 1 or 2 — never a signal (crash, abort) or another code;
  * exit 2 (invalid input): stderr names a JSON path, a file line or byte, or an option, and
    nothing was written;
  * exit 1 (numerical failure): summary.json exists and says "partial" (no "internal error");
  * exit 0: summary.json says "complete" and the files it promises exist and are not empty.

A run still going after --timeout seconds receives SIGINT, as a user pressing Ctrl-C: it must then
end with exit 130 and a summary flagged "partial" / "interrupted" (or, before its handlers are
installed, by the signal itself: verdict "timeout"). Either outcome satisfies the invariant, so
the verdicts do not depend on the machine's speed. Children run with a 2 GB address-space limit
(an input asking for more memory must fail cleanly, not take the machine).

Deterministic: input i of seed S is drawn from random.Random(f"{S}:{i}") and can be rerun alone
(--only i). Inputs that break the invariant are written with --save to the corpus folder
(tests/fuzz/corpus/structure/, one JSON file per input: command, exact case text) and every
corpus input is replayed before the random ones. Exit status 1 when any input breaks the
invariant, 0 otherwise. Counts per verdict are printed (docs/verification.md, "Robustness").
"""
import argparse
import copy
import functools
import glob
import hashlib
import json
import math
import os
import random
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile

ROOT_MARK = "@LSMBS_SOURCE_DIR@"
FILE_KEYS = {"file"}
NAME_ARRAYS = {"bodies", "joints", "forces", "measures", "responses", "variables", "features"}
ENUMS = {
    "type": ["rigid", "flexible", "revolute", "prismatic", "rigid_connection", "clamp", "rotation_driver",
             "translation_driver", "point_force", "spring_damper", "pressure", "point_mass", "torque",
             "rotational_spring_damper", "position", "velocity", "angle", "angular_velocity", "distance",
             "elongation", "path_deviation", "constraint_force", "kinetic_energy", "strain_energy", "mass",
             "trapezoid", "ramp", "table", "constant", "rectangle", "gmsh", "ellipse", "super_ellipse", "circle",
             "planar_chain"],
    "aggregate": ["average", "average_eq45", "max", "min", "final", "integral", "rms", "per_step", "ks"],
    "interpolation": ["cubic", "linear"],
    "integration": ["selective-shear", "full"],
    "newton": ["full", "modified", "modified_across_steps"],
    "ordering": ["amd", "nested_dissection"],
    "optimizer": ["mma", "ccsaq", "slsqp", "mma-svanberg"],
    "method": ["semi-analytical", "semi-analytical-central", "direct-analytic", "fd-forward", "fd-central", "idas",
               "idas-adjoint"],
    "matrix": ["last", "converged", "refined"],
    "delta_mode": ["relative", "absolute"],
    "phase": ["accelerate", "constant", "decelerate", "ramp"],
}
# Numbers that JSON cannot hold are written as tokens and substituted in the text.
SPECIAL = {"__NaN__": "NaN", "__Inf__": "Infinity", "__MInf__": "-Infinity", "__1e999__": "1e999",
           "__m1e999__": "-1e999"}


# ----------------------------------------------------------------------------- seeds
def rel_to_root(root, path):
    return ROOT_MARK + "/" + os.path.relpath(os.path.abspath(path), root)


def anchor_files(node, case_dir, root):
    """File references made relative to the source tree (ROOT_MARK), so a stored input replays anywhere."""
    if isinstance(node, dict):
        for k, v in node.items():
            if k in FILE_KEYS and isinstance(v, str):
                node[k] = rel_to_root(root, os.path.join(case_dir, v))
            else:
                anchor_files(v, case_dir, root)
    elif isinstance(node, list):
        for v in node:
            anchor_files(v, case_dir, root)


def load_seeds(root):
    seeds = []
    for f in sorted(glob.glob(os.path.join(root, "data", "**", "*.json"), recursive=True)):
        try:
            c = json.load(open(f))
        except ValueError:
            continue
        if isinstance(c, dict) and "bodies" in c and "simulation" in c:
            anchor_files(c, os.path.dirname(f), root)
            seeds.append((os.path.relpath(f, root), c))
    for f in sorted(glob.glob(os.path.join(root, "docs", "*.md"))):
        for k, block in enumerate(re.findall(r"```json\n(.*?)```", open(f).read(), re.S)):
            try:
                c = json.loads(block)
            except ValueError:
                continue
            if isinstance(c, dict) and "bodies" in c and "simulation" in c:
                seeds.append((f"{os.path.relpath(f, root)}#{k}", c))
    gen = os.path.join(root, "verification", "corpus")
    if os.path.isfile(os.path.join(gen, "gen_mechanisms.py")):
        sys.path.insert(0, gen)
        try:
            import gen_mechanisms
            for s in range(10):
                seeds.append((f"gen_mechanisms seed {s}", gen_mechanisms.generate(s, with_new_loads=s % 2 == 1)))
        except Exception as e:  # the generator is a convenience, not a requirement
            print(f"structure_fuzz: gen_mechanisms unavailable ({e})", file=sys.stderr)
    return seeds


def is_rigid(c):
    """No flexible (plane-stress) or solid body: a small case whose whole run is cheap."""
    return all(not (isinstance(b, dict) and b.get("type") in ("flexible", "solid"))
               for b in c.get("bodies", []))


def shorten(c, rng):
    """A few time steps (or the whole run of a small rigid case), windows dropped, few evaluations."""
    sim = c.get("simulation", {})
    h = sim.get("h")
    if isinstance(h, (int, float)) and h > 0 and not (is_rigid(c) and rng.random() < 0.3):
        sim["t_end"] = h * rng.choice([2, 3, 5, 8])
        out = c.get("output", {})
        for r in out.get("responses", []) if isinstance(out, dict) else []:
            if isinstance(r, dict):
                r.pop("window", None)
    opt = c.get("optimization")
    if isinstance(opt, dict):
        opt.setdefault("stop", {})["max_evaluations"] = rng.choice([1, 2, 3])
    out = c.get("output")
    if isinstance(out, dict) and out.get("vtu_stride", 0):
        out["vtu_stride"] = 1


# ----------------------------------------------------------------------------- mutations
def walk(node, path=""):
    """(parent, key, value, path) of every node below `node`."""
    if isinstance(node, dict):
        for k, v in list(node.items()):
            p = f"{path}/{k}"
            yield node, k, v, p
            yield from walk(v, p)
    elif isinstance(node, list):
        for i, v in enumerate(node):
            p = f"{path}/{i}"
            yield node, i, v, p
            yield from walk(v, p)


def pick(rng, doc, pred=lambda parent, key, value: True):
    cands = [n for n in walk(doc) if pred(n[0], n[1], n[2])]
    return rng.choice(cands) if cands else None


def is_num(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def names_in(doc):
    names = set()
    for parent, key, value, _ in walk(doc):
        if key == "name" and isinstance(value, str):
            names.add(value)
    return sorted(names)


def m_delete_key(rng, doc, ctx):
    n = pick(rng, doc, lambda p, k, v: isinstance(p, dict))
    if not n:
        return None
    del n[0][n[1]]
    return f"delete {n[3]}"


def m_retype(rng, doc, ctx):
    n = pick(rng, doc)
    if not n:
        return None
    choices = ["text", 1.5, 0, -3, [], {}, None, True, [1, 2, 3], {"x": 1}, [[0, 0], [1, 1]], "ground"]
    new = rng.choice([c for c in choices if type(c) is not type(n[2])])
    n[0][n[1]] = copy.deepcopy(new)
    return f"retype {n[3]} -> {json.dumps(new)}"


def m_number(rng, doc, ctx):
    n = pick(rng, doc, lambda p, k, v: is_num(v))
    if not n:
        return None
    v = n[2]
    new = rng.choice(["__NaN__", "__Inf__", "__MInf__", "__1e999__", "__m1e999__", 1e308, -1e308, 1.7e308, 1e-308,
                      5e-324, 0, 0.0, -0.0, -v, -1, v * 1e10, v * 1e-10, 2 ** 31, 2 ** 63, 2 ** 64, 1e20, 0.5, 2.5,
                      v + 1e-9, 123456789, v * 1e100, v * 1e-100, v * 1e300, v * 1e-300, v * (1 + 1e-15), 1e-300,
                      1e300])
    n[0][n[1]] = new
    return f"number {n[3]}: {v} -> {new}"


def m_empty(rng, doc, ctx):
    n = pick(rng, doc, lambda p, k, v: isinstance(v, (list, dict)))
    if not n:
        return None
    n[0][n[1]] = [] if rng.random() < 0.5 else {}
    return f"empty {n[3]}"


def m_duplicate_name(rng, doc, ctx):
    arrays = [(p, k, v, path) for p, k, v, path in walk(doc)
              if k in NAME_ARRAYS and isinstance(v, list) and len([x for x in v if isinstance(x, dict)]) >= 1]
    if not arrays:
        return None
    _, k, arr, path = rng.choice(arrays)
    objs = [x for x in arr if isinstance(x, dict)]
    a = rng.choice(objs)
    names = names_in(doc)
    if not names:
        return None
    a["name"] = rng.choice(names)
    if rng.random() < 0.3:  # or a second copy of a whole entry
        arr.append(copy.deepcopy(a))
    return f"duplicate name in {path}: {a['name']}"


def m_reference(rng, doc, ctx):
    names = names_in(doc)
    n = pick(rng, doc, lambda p, k, v: isinstance(v, str) and k not in ("name", "type", "file", "description",
                                                                        "comment") and not str(k).startswith("_"))
    if not n:
        return None
    new = rng.choice(names + ["ground", "nonexistent", "", "p", "rod", "x" * 5000, "a/b", "é", '"', "ground.mass"])
    n[0][n[1]] = new
    return f"reference {n[3]}: {n[2]!r} -> {new[:20]!r}"


def m_enum(rng, doc, ctx):
    n = pick(rng, doc, lambda p, k, v: k in ENUMS and isinstance(v, str))
    if not n:
        return None
    new = rng.choice(ENUMS[n[1]] + ["", "RIGID", "unknown"])
    n[0][n[1]] = new
    return f"enum {n[3]}: {n[2]} -> {new}"


def m_units(rng, doc, ctx):
    n = pick(rng, doc, lambda p, k, v: is_num(v) and v != 0)
    if not n:
        return None
    f = rng.choice([1e3, 1e-3, 1e6, 1e-6, 180 / math.pi, math.pi / 180, 1e9, 1e-9])
    n[0][n[1]] = n[2] * f
    return f"units {n[3]} x {f:g}"


def m_scale_subtree(rng, doc, ctx):
    """Every number of an entry in other units (a body in mm, a table in degrees, a mass in g)."""
    n = pick(rng, doc, lambda p, k, v: isinstance(v, (dict, list)))
    if not n:
        return None
    f = rng.choice([1e3, 1e-3, 180 / math.pi, 1e6, 1e-6, -1.0])

    def scale(x):
        if is_num(x):
            return x * f
        if isinstance(x, dict):
            return {k: scale(v) for k, v in x.items()}
        if isinstance(x, list):
            return [scale(v) for v in x]
        return x
    n[0][n[1]] = scale(n[2])
    return f"scale all numbers of {n[3]} x {f:g}"


def m_reorder(rng, doc, ctx):
    """Entries in another order (a measure or joint moved to the front, an array reversed)."""
    n = pick(rng, doc, lambda p, k, v: isinstance(v, list) and len(v) >= 2)
    if not n:
        return None
    arr = n[2]
    if rng.random() < 0.5:
        arr.reverse()
        return f"reverse {n[3]}"
    i = rng.randrange(1, len(arr))
    arr.insert(0, arr.pop(i))
    return f"move {n[3]}/{i} to the front"


def m_unknown_key(rng, doc, ctx):
    n = pick(rng, doc, lambda p, k, v: isinstance(v, dict))
    target = n[2] if n else doc
    key = rng.choice(["thickess", "masss", "Mass", "", " name", "_private", "comment", "t_end", "h", "x" * 300])
    target[key] = rng.choice([1, "x", None, [], {"a": 1}])
    return f"unknown key {n[3] if n else ''}/{key[:20]}"


def m_splice(rng, doc, ctx):
    a = pick(rng, doc)
    src = ctx["other"] if rng.random() < 0.5 else doc
    b = pick(rng, src)
    if not a or not b:
        return None
    a[0][a[1]] = copy.deepcopy(b[2])
    return f"splice {a[3]} <- {b[3]}"


def m_huge_array(rng, doc, ctx):
    n = pick(rng, doc, lambda p, k, v: isinstance(v, list) and len(v) > 0)
    if not n:
        return None
    count = rng.choice([1000, 5000, 20000])
    proto = n[2][-1]
    if isinstance(proto, dict) and "name" in proto and rng.random() < 0.7:
        arr = []
        for i in range(min(count, 2000)):
            e = copy.deepcopy(proto)
            e["name"] = f"{proto['name']}_{i}"
            arr.append(e)
    elif is_num(proto) or (isinstance(proto, list) and proto and is_num(proto[0])):
        arr = [copy.deepcopy(proto) if not is_num(proto) else proto + i for i in range(count)]
        if isinstance(proto, list) and len(proto) == 2 and is_num(proto[0]):  # table points: increasing x
            arr = [[proto[0] + i * 1e-3, proto[1]] for i in range(count)]
    else:
        arr = [copy.deepcopy(proto) for _ in range(min(count, 2000))]
    n[0][n[1]] = arr
    return f"huge array {n[3]} ({len(arr)} entries)"


def m_file(rng, doc, ctx):
    n = pick(rng, doc, lambda p, k, v: k in FILE_KEYS and isinstance(v, str))
    if not n:
        return None
    new = rng.choice([ROOT_MARK + "/data", "/dev/null", "/dev/zero", ROOT_MARK + "/data/nonexistent.msh",
                      ROOT_MARK + "/data/slider_crank/pressure.csv", ROOT_MARK + "/data/slider_crank/rod_coarse.msh",
                      ROOT_MARK + "/data/slider_crank/slider_crank_1hole.json", ROOT_MARK + "/README.md",
                      "@EMPTY_FILE@", "", "relative/missing.csv", "/proc/self/status"])
    n[0][n[1]] = new
    return f"file {n[3]} -> {new}"


def m_set_option(rng, doc, ctx):
    var = None
    d = doc.get("design") if isinstance(doc, dict) else None
    if isinstance(d, dict) and isinstance(d.get("variables"), list) and d["variables"]:
        v = d["variables"][0]
        var = v.get("name") if isinstance(v, dict) else None
    name = var if isinstance(var, str) and rng.random() < 0.8 else rng.choice(["p", "unknown", ""])
    val = rng.choice(["nan", "inf", "-1", "1e308", "abc", "0", "0.5", "1e-300", ""])
    ctx["extra_args"] += ["--set", f"{name}={val}"]
    return f"--set {name}={val}"


MUTATIONS = [(m_delete_key, 3), (m_retype, 3), (m_number, 8), (m_empty, 2), (m_duplicate_name, 2),
             (m_reference, 3), (m_enum, 2), (m_units, 3), (m_unknown_key, 1), (m_splice, 2), (m_huge_array, 1),
             (m_file, 1), (m_set_option, 1), (m_scale_subtree, 2), (m_reorder, 2)]
TEXT_MUTATIONS = ["truncate", "duplicate_key", "deep_nest", "garbage_byte"]


def to_text(doc):
    t = json.dumps(doc, indent=1, allow_nan=True)
    for tok, lit in SPECIAL.items():
        t = t.replace(json.dumps(tok), lit)
    return t


def text_mutation(rng, text, kind):
    if kind == "truncate":
        k = rng.randrange(len(text)) if text else 0
        return text[:k], f"truncate at byte {k}"
    if kind == "duplicate_key":  # the same key twice in an object: JSON allows it, the last one wins
        m = list(re.finditer(r'\n( *)"([^"\n]+)": ([^\n]*?),?\n', text))
        if not m:
            return text, "duplicate key (none)"
        x = rng.choice(m)
        dup = f'\n{x.group(1)}"{x.group(2)}": "duplicate",'
        return text[:x.start()] + dup + text[x.start():], f"duplicate key {x.group(2)}"
    if kind == "deep_nest":
        depth = rng.choice([100, 255, 257, 5000])
        m = list(re.finditer(r': (\d[^,\n]*)', text))
        if not m:
            return text, "deep nest (none)"
        x = rng.choice(m)
        return text[:x.start(1)] + "[" * depth + x.group(1) + "]" * depth + text[x.end(1):], f"deep nest {depth}"
    k = rng.randrange(len(text)) if text else 0
    ch = rng.choice(["\x00", "\xff", "{", "]", '"', "\\", "\u2028", ","])
    return text[:k] + ch + text[k + 1:], f"garbage byte {ch!r} at {k}"


def make_input(seeds, seed, i):
    rng = random.Random(f"{seed}:{i}")
    name, base = rng.choice(seeds)
    doc = copy.deepcopy(base)
    shorten(doc, rng)
    ctx = {"other": rng.choice(seeds)[1], "extra_args": []}
    ops = []
    for _ in range(rng.choices([1, 2, 3, 4], weights=[60, 25, 10, 5])[0]):
        f = rng.choices([m for m, _ in MUTATIONS], weights=[w for _, w in MUTATIONS])[0]
        try:
            d = f(rng, doc, ctx)
        except (TypeError, KeyError, IndexError, AttributeError):
            d = None
        if d:
            ops.append(d)
    text = to_text(doc)
    if rng.random() < 0.1:
        text, d = text_mutation(rng, text, rng.choice(TEXT_MUTATIONS))
        ops.append(d)
    command = "simulate"
    r = rng.random()
    if isinstance(doc, dict) and "design" in base:
        if r < 0.12:
            command = "sensitivity"
        elif r < 0.2 and "optimization" in base:
            command = "optimize"
        elif r < 0.24:
            command = "geometry"
    args = [command, "@CASE@", "-o", "@OUT@", "-q"]
    if command == "sensitivity":
        args += ["--method", rng.choice(["direct-analytic", "semi-analytical-central", "fd-forward"])]
    if command == "optimize":
        args += ["--no-check"]
    if command == "simulate" and rng.random() < 0.04:
        args += ["--integrator", "idas", "--rtol", rng.choice(["1e-6", "1e-9", "nan", "-1", "2"])]
    args += ctx["extra_args"]
    return {"seed_case": name, "mutations": ops, "command": args, "case_text": text}


# ----------------------------------------------------------------------------- running
LOCATION = re.compile(r"(^|[\s'\"(]|: )/[A-Za-z0-9_]*(/[^\s:]*)*:|byte \d+|line \d+|(^|\s)--?[a-z][a-z-]*[\s=:]|"
                      r"-o \S")


MEMORY_LIMIT = 2 << 30


@functools.lru_cache(maxsize=None)
def sanitized(exe):
    """AddressSanitizer reserves terabytes of address space: it gets its own allocation limit.
    The runtime is linked dynamically (libasan.so) or statically; either leaves __asan_init."""
    with open(exe, "rb") as f:
        return b"__asan_init" in f.read()


def limit_child(address_space=True):
    if address_space:
        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))


def files_promised(summary, out):
    """Files a complete summary names (files: every file the run wrote; every run: the summary itself)."""
    missing = []
    files = summary.get("files") if isinstance(summary, dict) else None
    if isinstance(files, (dict, list)):  # a list of every file written since issue 23
        for v in files.values() if isinstance(files, dict) else files:
            if isinstance(v, str):
                p = os.path.join(out, v)
                if not os.path.exists(p) or (os.path.isfile(p) and os.path.getsize(p) == 0):
                    missing.append(v)
    return missing


def finite(v):
    if isinstance(v, list):
        return all(finite(x) for x in v)
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def history_reaches_t_end(summary, out):
    """A complete simulation's history.csv ends at t_end (not before, not after); a case with
    service conditions: each condition's run in OUT/conditions/<name>/."""
    runs = glob.glob(os.path.join(out, "conditions", "*", "summary.json"))
    if "options" not in summary and runs:
        for f in sorted(runs):
            try:
                sub = json.load(open(f))
            except (OSError, ValueError) as e:
                return f"exit 0, complete, but {f} unreadable ({e!r})"
            why = history_reaches_t_end(sub, os.path.dirname(f))
            if why:
                return why + " (condition %s)" % os.path.basename(os.path.dirname(f))
        return None
    try:
        o = summary["options"]
        sim = o.get("generalized_alpha") or o.get("idas") or {}
        t_end = sim.get("t_end") or summary["options"].get("t_end")
        rows = open(os.path.join(out, "history.csv")).read().split("\n")
        rows = [r for r in rows if r and not r.startswith("#")]
        t_last = float(rows[-1].split(",")[0])
    except (KeyError, ValueError, IndexError, OSError, AttributeError, TypeError) as e:
        return f"exit 0, complete, but history.csv or options unreadable ({e!r})"
    if t_end is None:
        return None
    # rows every csv_stride steps: the last one within a stride of t_end, never after it
    stride = (o.get("output") or {}).get("csv_stride", 1)
    h = sim.get("h") or sim.get("h_out") or 0
    if not (len(rows) >= 3 and t_last <= t_end * (1 + 1e-12) and t_end - t_last <= stride * h * (1 + 1e-9)):
        return f"exit 0, complete, but history.csv ends at t = {t_last} ({len(rows) - 1} rows), t_end = {t_end}"
    for pvd in glob.glob(os.path.join(out, "*.pvd")):
        for f in re.findall(r'file="([^"]+)"', open(pvd).read()):
            p = os.path.join(out, f)
            if not os.path.isfile(p) or not os.path.getsize(p):
                return f"exit 0, complete, but {os.path.basename(pvd)} lists a missing or empty {f}"
    return None


def run_input(exe, root, inp, work, timeout):
    case = os.path.join(work, "case.json")
    out = os.path.join(work, "out")
    shutil.rmtree(out, ignore_errors=True)
    empty = os.path.join(work, "empty.msh")
    open(empty, "w").close()
    text = inp["case_text"].replace(ROOT_MARK, root).replace("@EMPTY_FILE@", empty)
    with open(case, "w", encoding="utf-8", errors="surrogatepass") as f:
        f.write(text)
    args = [exe] + [a.replace("@CASE@", case).replace("@OUT@", out) for a in inp["command"]]
    env = dict(os.environ)
    asan = sanitized(exe)
    if asan:  # allocations beyond the limit fail (std::bad_alloc) instead of aborting
        env["ASAN_OPTIONS"] = (env.get("ASAN_OPTIONS", "") + f":allocator_may_return_null=1"
                               f":max_allocation_size_mb={MEMORY_LIMIT >> 20}").lstrip(":")
    p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, cwd=work, env=env,
                         preexec_fn=lambda: limit_child(not asan))
    interrupted = False
    try:
        _, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        interrupted = True
        p.send_signal(signal.SIGINT)  # a user pressing Ctrl-C: the run must end cleanly
        try:
            _, err = p.communicate(timeout=max(30.0, 3 * timeout))
        except subprocess.TimeoutExpired:
            p.kill()
            _, err = p.communicate()
            return "hang", "no exit within the grace period after SIGINT", err.decode(errors="replace")
    rc = p.returncode
    err = err.decode(errors="replace")
    summary = None
    sp = os.path.join(out, "summary.json")
    if os.path.isfile(sp):
        try:
            summary = json.load(open(sp))
        except ValueError as e:
            return "violation", f"summary.json is not valid JSON ({e})", err
    status = summary.get("status") if isinstance(summary, dict) else None
    if rc < 0:
        if interrupted and rc == -signal.SIGINT:
            return "timeout", "ended by SIGINT before its interrupt handler was installed (setup)", err
        return "crash", f"killed by signal {signal.Signals(-rc).name}", err
    if "internal error" in err:
        return "violation", f"exit {rc} with an internal error", err
    if rc == 0:
        if status != "complete":
            return "violation", f"exit 0 but summary status {status!r}", err
        missing = files_promised(summary, out)
        if missing:
            return "violation", f"exit 0, complete, but files missing or empty: {missing}", err
        if inp["command"][0] in ("simulate", "sensitivity"):
            bad = [k for k, v in (summary.get("responses") or {}).items() if not finite(v)]
            if bad:
                return "violation", f"exit 0, complete, but responses not finite: {bad[:5]}", err
        if inp["command"][0] == "simulate":
            why = history_reaches_t_end(summary, out)
            if why:
                return "violation", why, err
        return "exit 0", "", err
    if rc == 1:
        if status not in ("partial", "refused"):
            return "violation", f"exit 1 but summary status {status!r}", err
        return "exit 1", "", err
    if rc == 2:
        if not LOCATION.search(err):
            return "violation", "exit 2 without a JSON path, file line or option in the message", err
        if os.path.isdir(out) and os.listdir(out):
            return "violation", f"exit 2 but wrote {sorted(os.listdir(out))[:5]}", err
        return "exit 2", "", err
    if rc == 130 and interrupted:
        if status not in ("partial", "interrupted"):
            return "violation", f"exit 130 after SIGINT but summary status {status!r}", err
        return "interrupted", "", err
    return "violation", f"unexpected exit code {rc}", err


BAD = ("crash", "violation", "hang")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--lsmbs", required=True)
    ap.add_argument("--root", default=os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("--only", type=int, default=None, help="run input number ONLY of the seed alone")
    ap.add_argument("--corpus", default=None, help="corpus folder (default tests/fuzz/corpus/structure)")
    ap.add_argument("--no-corpus", action="store_true", help="do not replay the corpus")
    ap.add_argument("--save", action="store_true", help="store inputs that break the invariant in the corpus")
    ap.add_argument("--timeout", type=float, default=3.0, help="seconds before a run gets SIGINT")
    ap.add_argument("--write", metavar="DIR", help="with --only: write the input's case.json to DIR and print the command")
    ap.add_argument("-v", "--verbose", action="store_true")
    a = ap.parse_args()
    root = os.path.abspath(a.root)
    exe = os.path.abspath(a.lsmbs)
    corpus = a.corpus or os.path.join(root, "tests", "fuzz", "corpus", "structure")
    seeds = load_seeds(root)
    if not seeds:
        print("structure_fuzz: no seed cases found", file=sys.stderr)
        return 2
    jobs = []
    if not a.no_corpus and a.only is None and os.path.isdir(corpus):
        for f in sorted(glob.glob(os.path.join(corpus, "*.json"))):
            jobs.append(("corpus " + os.path.basename(f), json.load(open(f))))
    indices = [a.only] if a.only is not None else range(a.count)
    for i in indices:
        jobs.append((f"seed {a.seed} input {i}", make_input(seeds, a.seed, i)))
    if a.write and a.only is not None:
        inp = jobs[-1][1]
        os.makedirs(a.write, exist_ok=True)
        case = os.path.join(a.write, "case.json")
        open(os.path.join(a.write, "empty.msh"), "w").close()
        with open(case, "w", encoding="utf-8", errors="surrogatepass") as f:
            f.write(inp["case_text"].replace(ROOT_MARK, root).replace("@EMPTY_FILE@", os.path.join(a.write, "empty.msh")))
        print(" ".join([exe] + [x.replace("@CASE@", case).replace("@OUT@", os.path.join(a.write, "out"))
                                for x in inp["command"]]))
        print("mutations: " + "; ".join(inp["mutations"]))
        return 0
    counts, bad = {}, []
    work = tempfile.mkdtemp(prefix="lsmbs_fuzz_")
    try:
        for label, inp in jobs:
            verdict, why, err = run_input(exe, root, inp, work, a.timeout)
            counts[verdict] = counts.get(verdict, 0) + 1
            if a.verbose or verdict in BAD or verdict == "timeout":
                print(f"{label}: {verdict} {why} | {inp.get('seed_case')} | {'; '.join(inp.get('mutations', []))[:300]} "
                      f"| {' '.join(inp['command'][:1] + inp['command'][5:])}")
                if verdict in BAD or a.verbose:
                    print("    stderr: " + err.strip().replace("\n", "\n    ")[:600])
            if verdict in BAD:
                bad.append(label)
                if a.save and not label.startswith("corpus"):
                    os.makedirs(corpus, exist_ok=True)
                    h = hashlib.sha1(inp["case_text"].encode("utf-8", "surrogatepass")).hexdigest()[:12]
                    rec = dict(inp, found=f"{verdict}: {why}")
                    with open(os.path.join(corpus, f"{verdict}_{h}.json"), "w") as f:
                        json.dump(rec, f, indent=1)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    n_corpus = sum(1 for l, _ in jobs if l.startswith("corpus"))
    print(f"structure_fuzz: seed {a.seed}, {len(jobs) - n_corpus} generated + {n_corpus} corpus inputs; verdicts: " +
          ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    if bad:
        print(f"structure_fuzz: {len(bad)} inputs broke the invariant: {', '.join(bad[:20])}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
