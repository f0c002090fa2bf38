#include "lsmbs/fem/solid_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/msh_reader.hpp"

namespace lsmbs {

namespace {

// The hexahedron's corners in its parent cube, in Gmsh's (and VTK's) node order.
constexpr double kHexCorner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                     {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

}  // namespace

std::string SolidMesh::node_set_names() const {
  std::string s;
  for (const auto& [name, nodes] : node_sets) s += (s.empty() ? "" : ", ") + name;
  return s.empty() ? "no node sets" : s;
}

double SolidMesh::size() const {
  if (nodes.empty()) return 0;
  Vec3 lo = nodes[0], hi = nodes[0];
  for (const Vec3& p : nodes) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).maxCoeff();
}

SolidMesh SolidMesh::box(const Vec3& origin, const Vec3& size, const std::array<int, 3>& n) {
  SolidMesh m;
  const int nx = n[0], ny = n[1], nz = n[2];
  const auto id = [&](int i, int j, int k) { return i + (nx + 1) * (j + (ny + 1) * k); };
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        m.nodes.push_back(origin + Vec3(size.x() * i / nx, size.y() * j / ny, size.z() * k / nz));
        const int node = id(i, j, k);
        if (i == 0) m.node_sets["xmin"].push_back(node);
        if (i == nx) m.node_sets["xmax"].push_back(node);
        if (j == 0) m.node_sets["ymin"].push_back(node);
        if (j == ny) m.node_sets["ymax"].push_back(node);
        if (k == 0) m.node_sets["zmin"].push_back(node);
        if (k == nz) m.node_sets["zmax"].push_back(node);
      }
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        m.cells.push_back({id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k),
                           id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1),
                           id(i, j + 1, k + 1)});
  return m;
}

SolidMesh SolidMesh::read_gmsh(const std::string& path) {
  MshFile f = read_msh41(path, 3, {{4, 4, "tet4", "tetrahedron"}, {5, 8, "hex8", "hexahedron"}});
  if (f.cells.empty())
    throw Error(path, "", "the mesh contains no 3-D cells (4-node tetrahedra or 8-node hexahedra)");
  f.check_coincident_nodes(path);
  for (MshCell& c : f.cells) {
    std::vector<Vec3> X;
    for (int k : c.nodes) X.push_back(f.nodes[static_cast<size_t>(k)]);
    double longest = 0;
    for (size_t i = 0; i < X.size(); ++i)
      for (size_t j = i + 1; j < X.size(); ++j) longest = std::max(longest, (X[i] - X[j]).norm());
    const std::string noun = X.size() == 4 ? "tetrahedron " : "hexahedron ";
    const Error folded(path, "line " + std::to_string(c.line),
                       noun + std::to_string(c.tag) +
                           " is inverted in part, self-intersecting or degenerate (det J changes "
                           "sign or vanishes at a Gauss point: its corners are not in Gmsh's "
                           "order, or it is flat or folded)");
    // a tetrahedron turned inside out is reordered; a hexahedron is too when its whole volume
    // is (its two faces swapped); one folded in part is refused
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    if (X.size() == 4) {
      Mat3 J;
      for (int k = 0; k < 3; ++k) J.col(k) = X[static_cast<size_t>(k + 1)] - X[0];
      lo = hi = J.determinant() / 6;
    } else {
      const double g = 1 / std::sqrt(3.0);
      for (int p = 0; p < 8; ++p) {
        const double s[3] = {g * kHexCorner[p][0], g * kHexCorner[p][1], g * kHexCorner[p][2]};
        Mat3 J = Mat3::Zero();
        for (int I = 0; I < 8; ++I) {
          const double a = 1 + s[0] * kHexCorner[I][0], b = 1 + s[1] * kHexCorner[I][1],
                       cc = 1 + s[2] * kHexCorner[I][2];
          J.col(0) += X[static_cast<size_t>(I)] * (kHexCorner[I][0] * b * cc / 8);
          J.col(1) += X[static_cast<size_t>(I)] * (a * kHexCorner[I][1] * cc / 8);
          J.col(2) += X[static_cast<size_t>(I)] * (a * b * kHexCorner[I][2] / 8);
        }
        lo = std::min(lo, J.determinant()), hi = std::max(hi, J.determinant());
      }
    }
    if (hi < 0) {
      if (X.size() == 4)
        std::swap(c.nodes[1], c.nodes[2]);
      else
        std::rotate(c.nodes.begin(), c.nodes.begin() + 4, c.nodes.end());
      std::swap(lo, hi);
      lo = -lo, hi = -hi;
    }
    if (!(lo > 0)) throw folded;
    // a sliver: its stiffness swamps every force near it in round-off
    const double volume = X.size() == 4 ? lo : 8 * lo;  // at most the volume
    const double flatness = volume / (longest * longest * longest);
    if (flatness < 1e-9) {
      char fl[32];
      std::snprintf(fl, sizeof fl, "%.3g", flatness);
      throw Error(path, "line " + std::to_string(c.line),
                  noun + std::to_string(c.tag) + " is nearly flat: its volume is " + fl +
                      " times its longest edge cubed (below 1e-9; a stiffness that swamps every "
                      "force near it in round-off); remove the sliver in Gmsh");
    }
  }
  f.drop_unused_nodes();
  SolidMesh m;
  m.nodes = f.nodes;
  for (const MshCell& c : f.cells) m.cells.push_back(c.nodes);
  for (const auto& [name, set] : f.sets)
    if (!set.empty()) m.node_sets[name].assign(set.begin(), set.end());
  return m;
}

}  // namespace lsmbs
