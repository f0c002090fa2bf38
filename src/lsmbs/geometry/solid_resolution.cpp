#include "lsmbs/geometry/solid_resolution.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <unordered_map>

#include "lsmbs/fem/solid_cell.hpp"
#include "lsmbs/geometry/length_scale_parts.hpp"
#include "lsmbs/geometry/solid_length_scale.hpp"

namespace lsmbs {
namespace {

// Cell e's extent along the unit direction d.
double extent(const SolidMesh& m, int e, const Vec3& d) {
  double lo = INFINITY, hi = -INFINITY;
  for (int k : m.cells[static_cast<size_t>(e)]) {
    const double t = d.dot(m.nodes[static_cast<size_t>(k)]);
    lo = std::min(lo, t), hi = std::max(hi, t);
  }
  return hi - lo;
}

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(static_cast<size_t>(n)) {
    std::iota(parent.begin(), parent.end(), 0);
  }
  int find(int a) {
    while (parent[static_cast<size_t>(a)] != a)
      a = parent[static_cast<size_t>(a)] =
          parent[static_cast<size_t>(parent[static_cast<size_t>(a)])];
    return a;
  }
  void join(int a, int b) { parent[static_cast<size_t>(find(a))] = find(b); }
};

// The volumes of the connected pieces of material, largest first (pieces below `smallest` out).
std::vector<double> pieces(const SolidLengthScale& L, const LevelSet3& ls,
                           const std::vector<std::vector<double>>& theta,
                           const std::vector<double>& D, double spacing, double smallest) {
  const int n = L.num_volume_samples();
  const double r = 1.01 * std::sqrt(3.0) * spacing;
  // a hash of the material samples by cube of side r
  auto key = [&](const Vec3& x) {
    const auto c = (x / r).array().floor().cast<long>();
    return (c[0] * 73856093L) ^ (c[1] * 19349663L) ^ (c[2] * 83492791L);
  };
  std::unordered_map<long, std::vector<int>> cubes;
  for (int k = 0; k < n; ++k)
    if (D[static_cast<size_t>(k)] > 0) cubes[key(L.volume_sample(k))].push_back(k);
  UnionFind uf(n);
  for (int k = 0; k < n; ++k) {
    if (!(D[static_cast<size_t>(k)] > 0)) continue;
    const Vec3& x = L.volume_sample(k);
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b)
        for (int c = -1; c <= 1; ++c) {
          const auto it = cubes.find(key(x + r * Vec3(a, b, c)));
          if (it == cubes.end()) continue;
          for (int j : it->second) {
            if (j <= k) continue;
            const Vec3& y = L.volume_sample(j);
            const double d = (x - y).norm();
            if (d > r) continue;
            // a boundary may pass between two samples nearer to it than their distance
            if (std::min(D[static_cast<size_t>(k)], D[static_cast<size_t>(j)]) < d &&
                !(ls.evaluate(0.5 * (x + y), theta, nullptr) > 0))
              continue;
            uf.join(k, j);
          }
        }
  }
  std::unordered_map<int, double> volume;
  for (int k = 0; k < n; ++k)
    if (D[static_cast<size_t>(k)] > 0) volume[uf.find(k)] += L.volume_weight(k);
  std::vector<double> v;
  for (const auto& [root, V] : volume)
    if (V >= smallest) v.push_back(V);
  std::sort(v.rbegin(), v.rend());
  return v;
}

}  // namespace

ResolutionReport judge_solid_resolution(const SolidMesh& mesh, const LevelSet3& ls, int num_design,
                                        const Vec& p, const ResolutionOptions& o) {
  ResolutionReport R;
  R.solid = true;
  R.element_size = median_longest_edge(mesh);
  R.threshold = o.min_elements * R.element_size;
  R.spacing = R.element_size / o.samples_per_element;
  LengthScaleOptions lo;
  lo.min_ligament = lo.min_member = R.threshold;  // edges: face by face, below
  lo.tolerance = 1e-3;
  lo.spacing = R.spacing;
  const SolidLengthScale L(mesh, ls, num_design, lo);
  const auto theta = ls.values(p);
  const auto& F = ls.features();
  const int nf = static_cast<int>(F.size());
  const std::vector<char> voids = length_scale_parts::void_features(ls.root(), F);
  // the level set at the volume samples; a feature bounds void where it is the level set's
  // active leaf at its zero: a sample within a spacing of the zero where the level set equals
  // ± the feature's own distance (a hole inside another, or in an OR of holes, or wholly outside
  // the body, bounds none, and has no part to judge)
  const int n = L.num_volume_samples();
  std::vector<double> D(static_cast<size_t>(n));
  std::vector<char> bounds(static_cast<size_t>(nf), 0);
  for (int k = 0; k < n; ++k) {
    const Vec3& x = L.volume_sample(k);
    const double d = D[static_cast<size_t>(k)] = ls.evaluate(x, theta, nullptr);
    if (!(std::abs(d) < R.spacing)) continue;
    for (int i = 0; i < nf; ++i) {
      if (bounds[static_cast<size_t>(i)]) continue;
      const double di =
          F[static_cast<size_t>(i)].distance<double>(x, theta[static_cast<size_t>(i)].data(), 0);
      if (std::min(std::abs(d - di), std::abs(d + di)) < 0.25 * R.spacing)
        bounds[static_cast<size_t>(i)] = 1;
    }
  }
  std::vector<Vec3> centroid;
  for (const auto& cell : mesh.cells) {
    Vec3 c = Vec3::Zero();
    for (int k : cell) c += mesh.nodes[static_cast<size_t>(k)];
    centroid.push_back(c / static_cast<double>(cell.size()));
  }
  auto cell_near = [&](const Vec3& x) {
    int best = 0;
    for (int e = 1; e < mesh.num_elements(); ++e)
      if ((centroid[static_cast<size_t>(e)] - x).squaredNorm() <
          (centroid[static_cast<size_t>(best)] - x).squaredNorm())
        best = e;
    return best;
  };
  auto index = [&](const std::string& name) {
    for (int i = 0; i < nf; ++i)
      if (F[static_cast<size_t>(i)].name() == name) return i;
    return -1;
  };
  auto judged = [&](int i) {
    return i >= 0 && i < num_design && voids[static_cast<size_t>(i)] &&
           bounds[static_cast<size_t>(i)];
  };
  // ∇s_i(x) by central differences (s is a distance: |∇s| = 1 off its medial set)
  const double eta = 1e-6 * R.element_size;
  auto gradient = [&](int i, const Vec3& x) {
    Vec3 g;
    for (int k = 0; k < 3; ++k) {
      Vec3 a = x, b = x;
      a[k] += eta, b[k] -= eta;
      g[k] = (L.shape_distance(i, a, theta) - L.shape_distance(i, b, theta)) / (2 * eta);
    }
    return g;
  };
  // the direction from feature i's centre c in which its boundary is nearest (of width w); of
  // directions as near (a circle's, a sphere's), the one across which cell e is thinnest
  auto narrowest = [&](int i, const Vec3& c, double w, int e) {
    const Feature3& f = F[static_cast<size_t>(i)];
    const Mat3& A = f.frame().axes;
    std::vector<Vec3> dirs;
    for (int k = 0; k < 16; ++k) {
      const double t = std::numbers::pi * k / 16;
      dirs.push_back(std::cos(t) * A.col(0) + std::sin(t) * A.col(1));
    }
    if (f.type() != Feature3::Type::kPocket && f.type() != Feature3::Type::kThroughHole)
      dirs.push_back(A.col(2));
    std::vector<double> probe;
    for (const Vec3& d : dirs) probe.push_back(L.shape_distance(i, c + 0.45 * w * d, theta));
    const double top = *std::max_element(probe.begin(), probe.end());
    Vec3 best = dirs.front();
    double thinnest = INFINITY;
    for (size_t k = 0; k < dirs.size(); ++k)
      if (probe[k] >= top - 1e-6 * w)
        if (const double x = extent(mesh, e, dirs[k]); x < thinnest) thinnest = x, best = dirs[k];
    return best;
  };
  auto add = [&](NarrowPart q, const Vec3& x, Vec3 d) {
    d = d.norm() > 0 ? Vec3(d.normalized()) : Vec3::UnitX();
    q.at = x;
    q.threshold = o.min_elements * extent(mesh, cell_near(x), d);
    q.unresolved = q.width < q.threshold;
    R.parts.push_back(std::move(q));
  };
  for (const LengthScaleConstraint& c : L.evaluate(p)) {
    const int i = index(c.first), j = c.second.empty() ? -1 : index(c.second);
    const Vec3 x(c.at[0], c.at[1], c.at[2]);
    NarrowPart q;
    q.first = c.first, q.second = c.second, q.width = c.value;
    if (c.kind == "member") {
      if (!judged(i)) continue;
      q.kind = NarrowPart::Kind::kHole;
      add(q, x, narrowest(i, x, c.value, cell_near(x)));
    } else if (c.kind == "ligament") {
      // overlapping features have merged into one void; a non-design region is material itself
      if (c.value < 0 || c.value >= 3 * R.threshold || !judged(i) || !judged(j)) continue;
      // across the ligament: off the segment between the nearest points the two gradients tilt
      // in opposite directions, and their difference keeps to the segment's
      q.kind = NarrowPart::Kind::kLigament;
      add(q, x, gradient(i, x) - gradient(j, x));
    }
  }
  // the material between each feature and each face it does not open, across the face; a
  // feature that breaks through one face (a notch) still has its flanges to the others judged
  for (int i = 0; i < num_design; ++i) {
    if (!judged(i)) continue;
    for (const auto& f : L.face_distances(i, theta, 3 * R.threshold)) {
      if (!(f.value > 0)) continue;
      NarrowPart q;
      q.kind = NarrowPart::Kind::kLigament;
      q.first = F[static_cast<size_t>(i)].name(), q.second = "surface", q.width = f.value;
      add(q, f.at, f.normal);
    }
  }
  std::stable_sort(R.parts.begin(), R.parts.end(),
                   [](const NarrowPart& a, const NarrowPart& b) { return a.width < b.width; });
  std::vector<double> V;
  for (int e = 0; e < mesh.num_elements(); ++e) V.push_back(cell_volume(mesh, e));
  std::nth_element(V.begin(), V.begin() + static_cast<long>(V.size() / 2), V.end());
  R.pieces = pieces(L, ls, theta, D, R.spacing, 0.5 * V[V.size() / 2]);
  R.piece_spacing = R.spacing;
  return R;
}

}  // namespace lsmbs
