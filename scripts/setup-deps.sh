#!/usr/bin/env bash
# Installs the Debian packages lsmbs builds and tests with, only those missing.
# Idempotent, non-interactive, quiet when everything is present.
#   scripts/setup-deps.sh [--with-gmsh] [--with-vtk] [--with-hypre]
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libsundials-dev libeigen3-dev libsuitesparse-dev libnlopt-cxx-dev
  # an optimized BLAS for UMFPACK's frontal matrices (3D solid meshes: 3.4x faster factorizations
  # than the reference BLAS, docs/performance.md); serial, so that results do not depend on
  # thread counts. Debian's alternatives make it the libblas.so.3 every program loads.
  libopenblas0-serial
  nlohmann-json3-dev libcli11-dev libgtest-dev libbenchmark-dev zlib1g-dev
  libcairo2-dev fonts-dejavu-core
  clang-format
  pybind11-dev python3-pybind11 python3-numpy python3-pytest python3-scipy python3-matplotlib
  python3-pandas python3-yaml python3-pil
  # design export (DXF, SVG, STEP, body-fitted meshes: lsmbs.export, lsmbs export)
  python3-ezdxf python3-gmsh
  # MPI (optional at build time: without it lsmbs builds, and the campaigns use local cores)
  libopenmpi-dev openmpi-bin
  # hypre (with MPI): the AMG linear solver for large 3D solid meshes ("linear_solver": "amg",
  # docs/performance.md "Linear solvers on 3D meshes"); optional at build time like MPI
  libhypre-dev
)

# --with-gmsh: also the Gmsh command line, to re-mesh data/slider_crank/rod.geo (the shipped
# .msh files are committed; lsmbs itself reads .msh and needs no Gmsh)
# --with-vtk: also VTK's Python module, with which tests/python/test_vtk_reader.py reads the
# VTU/VTM/PVD output as ParaView does (skipped where `import vtk` fails; lsmbs needs no VTK)
# --with-hypre: accepted for older instructions; hypre is among the packages above
for arg in "$@"; do
  case $arg in
    --with-gmsh) packages+=(gmsh) ;;
    --with-vtk) packages+=(python3-vtk9) ;;
    --with-hypre) ;;
    *) echo "setup-deps: unknown option $arg (expected --with-gmsh, --with-vtk or --with-hypre)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "setup-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup-deps: done"
