#!/usr/bin/env python3
"""CITATION.cff is valid YAML with the fields Citation File Format 1.2.0 requires (cff-version,
message, title, authors; the same for a preferred citation, plus its type), cites the paper the
code implements (title and authors as in shared/paper), and names the licence of LICENSE.
Usage: citation_test.py SOURCE_DIR (Debian's python3 with python3-yaml)."""
import datetime
import os
import re
import sys

import yaml

src = sys.argv[1]
c = yaml.safe_load(open(os.path.join(src, "CITATION.cff"), encoding="utf-8"))


def person_ok(a):
    return isinstance(a, dict) and (isinstance(a.get("family-names"), str) or isinstance(a.get("name"), str))


assert c["cff-version"] == "1.2.0", c["cff-version"]
for key in ("message", "title"):
    assert isinstance(c[key], str) and c[key].strip(), key
assert c["type"] in ("software", "dataset"), c["type"]
assert isinstance(c["authors"], list) and c["authors"] and all(person_ok(a) for a in c["authors"]), c["authors"]
version = re.search(r"project\(lsmbs VERSION ([0-9.]+)", open(os.path.join(src, "CMakeLists.txt")).read()).group(1)
assert str(c["version"]) == version, (c["version"], version)

p = c["preferred-citation"]
assert p["type"] == "article" and all(person_ok(a) for a in p["authors"])
assert p["title"] == "Structural optimization of multibody system components described using level set techniques"
assert [a["family-names"] for a in p["authors"]] == ["Tromme", "Tortorelli", "Brüls", "Duysinx"]
assert p["journal"] == "Structural and Multidisciplinary Optimization"
assert isinstance(p["year"], int) and 1900 < p["year"] <= datetime.date.today().year
assert isinstance(p["start"], int) and isinstance(p["end"], int) and p["start"] < p["end"]

lic = open(os.path.join(src, "LICENSE")).read()
assert c["license"] == "MIT" and lic.startswith("MIT License") and "the lsmbs authors" in lic
print(f"CITATION.cff: cff-version {c['cff-version']}, lsmbs {c['version']}, preferred citation "
      f"{p['authors'][0]['family-names']} et al. {p['year']}; LICENSE {c['license']}")
