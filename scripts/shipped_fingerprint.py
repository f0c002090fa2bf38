#!/usr/bin/env python3
"""Fingerprint of the shipped cases: the `responses` and `gradients` of every data/ case.

Used around refactorings that must not change a number (docs/architecture.md): run it with the
binary before and after, then compare the two files; they must be identical.

  scripts/shipped_fingerprint.py BINARY OUT.json      # write the fingerprint
  scripts/shipped_fingerprint.py --compare A.json B.json   # exit 1 on any difference

Cases with a design section: `sensitivity` with direct-analytic and semi-analytical (its own Δp);
the others: `simulate`. Numbers are kept as JSON numbers (17 significant digits, round trip).
"""
import json
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
KEYS = ("responses", "gradients", "quadratures")


def run(binary, case, args):
    with tempfile.TemporaryDirectory() as out:
        p = subprocess.run([binary, *args, str(case), "-o", out, "-q"], capture_output=True, text=True)
        if p.returncode != 0:
            return {"exit": p.returncode, "stderr": p.stderr.strip()}
        s = json.loads((pathlib.Path(out) / "summary.json").read_text())
        return {k: s[k] for k in KEYS if k in s}


def fingerprint(binary):
    fp = {}
    for case in sorted((ROOT / "data").rglob("*.json")):
        doc = json.loads(case.read_text())
        if not isinstance(doc, dict) or "bodies" not in doc:
            continue
        rel = str(case.relative_to(ROOT))
        if "design" in doc and doc.get("output", {}).get("responses"):
            for m in ("direct-analytic", "semi-analytical"):
                fp[rel + " sensitivity " + m] = run(binary, case, ["sensitivity", "--method", m])
        else:
            fp[rel + " simulate"] = run(binary, case, ["simulate"])
        print(rel, file=sys.stderr)
    return fp


def main():
    if sys.argv[1] == "--compare":
        a, b = (json.loads(pathlib.Path(f).read_text()) for f in sys.argv[2:4])
        bad = [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
        for k in bad:
            print("differs:", k)
        print(f"{len(a)} runs compared, {len(bad)} differ")
        return 1 if bad else 0
    pathlib.Path(sys.argv[2]).write_text(json.dumps(fingerprint(sys.argv[1]), indent=1, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
