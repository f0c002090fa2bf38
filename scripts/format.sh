#!/usr/bin/env bash
# Applies the project's .clang-format to every C++ source of the repository (src, tests,
# examples, bench, verification).
#   scripts/format.sh           reformat in place
#   scripts/format.sh --check   change nothing; list the files that differ and exit 1 if any
# The layout is clang-format's (Debian's clang-format, the version scripts/setup-deps.sh installs).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
command -v clang-format >/dev/null || bash scripts/setup-deps.sh
mapfile -t files < <(git ls-files -- 'src/*.cpp' 'src/*.hpp' 'src/*.hpp.in' 'tests/*.cpp' 'tests/*.hpp' \
  'examples/*.cpp' 'examples/*.hpp' 'python/*.cpp' 'bench/*.cpp' 'bench/*.hpp' 'verification/*.cpp' 'verification/*.hpp' |
  grep -v '\.in$')
if [ "${1:-}" = "--check" ]; then
  bad=()
  for f in "${files[@]}"; do
    if ! clang-format --dry-run --Werror "$f" >/dev/null 2>&1; then bad+=("$f"); fi
  done
  if [ ${#bad[@]} -gt 0 ]; then
    echo "format: ${#bad[@]} of ${#files[@]} files differ from .clang-format (scripts/format.sh fixes them):"
    printf '  %s\n' "${bad[@]}"
    exit 1
  fi
  echo "format: ${#files[@]} files follow .clang-format"
  exit 0
fi
clang-format -i "${files[@]}"
echo "format: ${#files[@]} files formatted"
