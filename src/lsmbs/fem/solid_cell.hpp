#pragma once
// The geometry of one cell of a SolidMesh: a hexahedron's trilinear map from its parent cube
// [−1, 1]³ (corners in the order of fem/hex_element.hpp) and the faces of both cell kinds.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "lsmbs/fem/solid_mesh.hpp"

namespace lsmbs {

/// The parent coordinates of a hexahedron's corners.
inline constexpr double kHexCorner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                            {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

/// A hexahedron's faces: (the parent axis it is normal to, its side ±1), corners in order round.
struct HexFace {
  int axis;
  double side;
  std::array<int, 4> corners;
};
inline constexpr std::array<HexFace, 6> kHexFaces = {{{0, -1, {0, 3, 7, 4}},
                                                      {0, 1, {1, 2, 6, 5}},
                                                      {1, -1, {0, 1, 5, 4}},
                                                      {1, 1, {3, 2, 6, 7}},
                                                      {2, -1, {0, 1, 2, 3}},
                                                      {2, 1, {4, 5, 6, 7}}}};
/// A tetrahedron's faces, each opposite the corner missing from it.
inline constexpr std::array<std::array<int, 3>, 4> kTetFaces = {
    {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}}};

/// Hexahedron e's point at parent coordinates s, and det(∂x/∂s) there.
inline Vec3 hex_point(const SolidMesh& m, int e, const Vec3& s, double& detJ) {
  Vec3 x = Vec3::Zero();
  Mat3 J = Mat3::Zero();  // ∂x/∂s
  const auto& cell = m.cells[static_cast<size_t>(e)];
  for (int I = 0; I < 8; ++I) {
    const double a = 1 + s[0] * kHexCorner[I][0], b = 1 + s[1] * kHexCorner[I][1],
                 c = 1 + s[2] * kHexCorner[I][2];
    const Vec3& X = m.nodes[static_cast<size_t>(cell[static_cast<size_t>(I)])];
    x += X * (a * b * c / 8);
    J.col(0) += X * (kHexCorner[I][0] * b * c / 8);
    J.col(1) += X * (a * kHexCorner[I][1] * c / 8);
    J.col(2) += X * (a * b * kHexCorner[I][2] / 8);
  }
  detJ = J.determinant();
  return x;
}

/// Cell e's volume: a hexahedron's by 2 × 2 × 2 Gauss points (exact for trilinear ones), a
/// tetrahedron's exactly.
inline double cell_volume(const SolidMesh& m, int e) {
  const auto& c = m.cells[static_cast<size_t>(e)];
  double detJ = 0, V = 0;
  if (c.size() == 8) {
    const double g = 1 / std::sqrt(3.0);
    for (const auto& k : kHexCorner) {
      hex_point(m, e, Vec3(g * k[0], g * k[1], g * k[2]), detJ);
      V += detJ;
    }
    return std::abs(V);
  }
  Mat3 J;
  for (int k = 0; k < 3; ++k)
    J.col(k) = m.nodes[static_cast<size_t>(c[static_cast<size_t>(k + 1)])] -
               m.nodes[static_cast<size_t>(c[0])];
  return std::abs(J.determinant()) / 6;
}

/// Cell e's longest edge (of a hexahedron: corner pairs one parent axis apart).
inline double longest_edge(const SolidMesh& m, int e) {
  const auto& cell = m.cells[static_cast<size_t>(e)];
  double edge = 0;
  for (size_t i = 0; i < cell.size(); ++i)
    for (size_t j = i + 1; j < cell.size(); ++j) {
      if (cell.size() == 8) {
        int differ = 0;
        for (int k = 0; k < 3; ++k) differ += kHexCorner[i][k] != kHexCorner[j][k];
        if (differ != 1) continue;
      }
      edge = std::max(
          edge,
          (m.nodes[static_cast<size_t>(cell[i])] - m.nodes[static_cast<size_t>(cell[j])]).norm());
    }
  return edge;
}

/// The median of the cells' longest edges [m]: the element size of a solid mesh (0 without cells).
inline double median_longest_edge(const SolidMesh& m) {
  std::vector<double> h;
  for (int e = 0; e < m.num_elements(); ++e) h.push_back(longest_edge(m, e));
  if (h.empty()) return 0;
  std::nth_element(h.begin(), h.begin() + static_cast<long>(h.size() / 2), h.end());
  return h[h.size() / 2];
}

}  // namespace lsmbs
