#!/usr/bin/env python3
"""The workflow layer, the command line and the Python module stay readable: no function in
src/lsmbs/runs, src/app or python is longer than 80 lines unless a `// long-function:` comment
above it says why (docs/architecture.md). The counter is checked first on a made-up file whose
function lengths are known, so that a counter that finds nothing cannot pass the real check."""
import pathlib
import subprocess
import sys
import tempfile

root = pathlib.Path(sys.argv[1])
script = root / "scripts" / "long_functions.py"
sys.path.insert(0, str(script.parent))
import long_functions  # noqa: E402


def body(n):
    return "".join(f"  x += {i};\n" for i in range(n))


with tempfile.TemporaryDirectory() as tmp:
    f = pathlib.Path(tmp) / "sample.cpp"
    f.write_text(
        "namespace a {\n\n"
        "int short_one(int x) {\n" + body(10) + "  return x;\n}\n\n"
        "static std::vector<int> long_one(int x,\n                                 int y) {\n"
        + body(90) + "  return {x};\n}\n\n"
        "// long-function: a table written out\n"
        "int excused(int x) {\n" + body(100) + "  return x;\n}\n\n"
        "}  // namespace a\n")
    found = {name: (length, reason) for name, _, length, reason in long_functions.functions(str(f))}
    assert found["short_one"][0] == 13, found
    assert found["long_one"][0] == 94, found
    assert found["excused"] == (103, "a table written out"), found
    strict = subprocess.run([sys.executable, str(script), "--strict", str(f)], capture_output=True,
                            text=True)
    assert strict.returncode == 1 and "long_one: 94 lines" in strict.stdout, strict

r = subprocess.run([sys.executable, str(script), "--strict", str(root / "src/lsmbs/runs"),
                    str(root / "src/app"), str(root / "python")], capture_output=True, text=True)
print(r.stdout, r.stderr)
sys.exit(r.returncode)
