#include "lsmbs/fem/solid_mesh.hpp"

#include <algorithm>

namespace lsmbs {

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

}  // namespace lsmbs
