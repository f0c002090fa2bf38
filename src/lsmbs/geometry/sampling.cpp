#include "lsmbs/geometry/sampling.hpp"

#include <algorithm>
#include <cmath>

namespace lsmbs {
namespace {

// Whether x lies in the convex polygon P (counter-clockwise), boundary included.
bool in_polygon(const Vec2& x, const std::array<Vec2, Cell::kMaxNodes>& P, int n) {
  for (int k = 0; k < n; ++k) {
    const Vec2 a = P[static_cast<size_t>(k)], b = P[static_cast<size_t>((k + 1) % n)];
    const Vec2 e = b - a, r = x - a;
    if (e.x() * r.y() - e.y() * r.x() < -1e-12 * e.squaredNorm()) return false;
  }
  return true;
}

}  // namespace

bool SampleGrid::covers(const Vec2& x) const {
  const int i = static_cast<int>(std::floor((x.x() - lo.x()) / s));
  const int j = static_cast<int>(std::floor((x.y() - lo.y()) / s));
  return i >= 0 && j >= 0 && i < nx && j < ny && inside[static_cast<size_t>(index(i, j))];
}

SampleGrid make_sample_grid(const Mesh2D& mesh, double spacing) {
  SampleGrid g;
  Vec2 lo = mesh.nodes.front(), hi = lo;
  for (const Vec2& x : mesh.nodes) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  g.lo = lo;
  g.s = spacing;
  g.nx = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / spacing)));
  g.ny = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / spacing)));
  g.inside.assign(static_cast<size_t>(g.nx) * g.ny, 0);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto P = mesh.cell_nodes(e);
    const int n = mesh.cells[static_cast<size_t>(e)].size();
    Vec2 a = P[0], b = P[0];
    for (int k = 1; k < n; ++k)
      a = a.cwiseMin(P[static_cast<size_t>(k)]), b = b.cwiseMax(P[static_cast<size_t>(k)]);
    const int i0 = std::max(0, static_cast<int>(std::floor((a.x() - lo.x()) / spacing - 0.5)));
    const int j0 = std::max(0, static_cast<int>(std::floor((a.y() - lo.y()) / spacing - 0.5)));
    const int i1 = std::min(g.nx - 1, static_cast<int>(std::ceil((b.x() - lo.x()) / spacing)));
    const int j1 = std::min(g.ny - 1, static_cast<int>(std::ceil((b.y() - lo.y()) / spacing)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i)
        if (in_polygon(g.point(i, j), P, n)) g.inside[static_cast<size_t>(g.index(i, j))] = 1;
  }
  return g;
}

double median_element_size(const Mesh2D& mesh) {
  std::vector<double> h;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto P = mesh.cell_nodes(e);
    const int n = mesh.cells[static_cast<size_t>(e)].size();
    double a = 0;  // shoelace
    for (int k = 0; k < n; ++k) {
      const Vec2 p = P[static_cast<size_t>(k)], q = P[static_cast<size_t>((k + 1) % n)];
      a += p.x() * q.y() - p.y() * q.x();
    }
    h.push_back(std::sqrt(std::abs(a) / 2));
  }
  if (h.empty()) return 0;
  std::nth_element(h.begin(), h.begin() + static_cast<long>(h.size() / 2), h.end());
  return h[h.size() / 2];
}

}  // namespace lsmbs
