#include "lsmbs/geometry/resolution.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>

#include "lsmbs/geometry/bspline.hpp"
#include "lsmbs/geometry/sampling.hpp"

namespace lsmbs {
namespace {

// Feet of two boundaries whose directions from x are closer than this (cosine) than opposite do
// not bound a ligament: x is in a corner of material (a hole meeting the outer edge at a right
// angle has its feet 90° apart at the corner's bisector). Above it, a wedge of material sharper
// than about 45° counts as narrow there.
constexpr double kOppositeCos = -0.7;

// The mesh's outer edges (of every boundary loop).
std::vector<std::pair<Vec2, Vec2>> outer_edges(const Mesh2D& mesh) {
  std::vector<std::pair<Vec2, Vec2>> edges;
  for (const auto& loop : mesh.boundary_loops())
    for (size_t k = 0; k < loop.size(); ++k)
      edges.emplace_back(mesh.nodes[static_cast<size_t>(loop[k])],
                         mesh.nodes[static_cast<size_t>(loop[(k + 1) % loop.size()])]);
  return edges;
}

// Distance from x to the nearest outer edge and the unit direction towards it.
double edge_distance(const Vec2& x, const std::vector<std::pair<Vec2, Vec2>>& edges, Vec2& dir) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [a, b] : edges) {
    const Vec2 e = b - a;
    const double t = std::clamp((x - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    const Vec2 y = a + t * e;
    const double d = (y - x).norm();
    if (d < best) best = d, dir = d > 0 ? Vec2((y - x) / d) : Vec2::Zero();
  }
  return best;
}

// n points of the feature's exact boundary (eqs. 41, 43) at parameter values th.
std::vector<Vec2> boundary_polygon(const Feature& f, const double* th, int n) {
  if (f.type() == Feature::Type::kBSpline) {
    const ClosedBSpline curve(th, static_cast<int>(f.params().size() / 2));
    return curve.polygon(std::max(1, n / curve.size()));
  }
  const bool ell = f.type() == Feature::Type::kEllipse,
             sup = f.type() == Feature::Type::kSuperEllipse;
  const double ang = ell ? th[5] : sup ? th[6] : 0, c = std::cos(ang), s = std::sin(ang);
  std::vector<Vec2> P;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * std::numbers::pi * k / n, ct = std::cos(t), st = std::sin(t);
    double u, v;
    if (ell)
      u = th[2] * th[4] * ct, v = th[3] * th[4] * st;
    else if (sup)
      u = th[2] * std::copysign(std::pow(std::abs(ct), 2 / th[4]), ct),
      v = th[3] * std::copysign(std::pow(std::abs(st), 2 / th[5]), st);
    else
      u = th[2] * ct, v = th[2] * st;
    P.emplace_back(th[0] + c * u - s * v, th[1] + s * u + c * v);
  }
  return P;
}

double polygon_distance(const Vec2& x, const std::vector<Vec2>& P) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < P.size(); ++k) {
    const Vec2 a = P[k], e = P[(k + 1) % P.size()] - a;
    const double t = std::clamp((x - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * e - x).norm());
  }
  return best;
}

// A boundary near x: its index (features, then the outer edge), distance, direction to its foot.
struct Near {
  int entity = -1;
  double r = std::numeric_limits<double>::infinity();
  Vec2 dir = Vec2::Zero();
};

std::string width_text(double w) {
  char b[48];
  std::snprintf(b, sizeof b, "%.3g mm", w * 1e3);
  return b;
}

std::string at_text(const Vec& x) {
  char b[96];
  if (x.size() == 3)
    std::snprintf(b, sizeof b, "(%.4g, %.4g, %.4g) m", x[0], x[1], x[2]);
  else
    std::snprintf(b, sizeof b, "(%.4g, %.4g) m", x[0], x[1]);
  return b;
}

std::string side_text(const std::string& s) {
  return s == "outer edge" ? "the outer edge"
         : s == "surface"  ? "the surface"
                           : "feature '" + s + "'";
}

}  // namespace

std::vector<std::string> ResolutionReport::flags() const {
  std::vector<std::string> f;
  for (const NarrowPart& p : parts) {
    if (!p.unresolved) continue;
    char cells[96];
    std::snprintf(cells, sizeof cells, " (%.3g cells of %s across it)", threshold / element_size,
                  width_text(p.threshold * element_size / threshold).c_str());
    const std::string limit =
        width_text(p.threshold) + (solid ? cells : " (" + width_text(element_size) + " elements)");
    if (p.kind == NarrowPart::Kind::kHole)
      f.push_back("feature '" + p.first + "' is " + width_text(p.width) + " wide at " +
                  at_text(p.at) + ", below the " + limit + " the mesh resolves");
    else
      f.push_back("the material between " +
                  (p.first == "outer edge" ? p.first : "feature '" + p.first + "'") + " and " +
                  side_text(p.second) + " is " + width_text(p.width) + " wide at " + at_text(p.at) +
                  ", below the " + limit + " the mesh resolves");
  }
  return f;
}

std::string ResolutionReport::pieces_flag() const {
  if (pieces.size() <= 1) return {};
  std::string a;
  for (size_t k = 0; k < pieces.size(); ++k) {
    char b[32];
    std::snprintf(b, sizeof b, "%s%.4g", k ? ", " : "", pieces[k] * (solid ? 1e9 : 1e6));
    a += b;
  }
  char w[32];
  std::snprintf(w, sizeof w, "%.2g mm", piece_spacing * 1e3);
  return "the material falls apart into " + std::to_string(pieces.size()) + " pieces (" +
         (solid ? "volumes " : "areas ") + a + (solid ? " mm³" : " mm²") +
         "; joined, if at all, by less than " + w + "): all but one hang on ersatz material";
}

ResolutionReport judge_resolution(const Mesh2D& mesh, const LevelSet& ls, const LevelSet::Values& v,
                                  const ResolutionOptions& o) {
  ResolutionReport R;
  if (mesh.num_elements() == 0) return R;
  R.element_size = median_element_size(mesh);
  R.spacing = R.element_size / std::max(1, o.samples_per_element);
  R.threshold = o.min_elements * R.element_size;
  const SampleGrid g = make_sample_grid(mesh, R.spacing);
  const auto edges = outer_edges(mesh);
  const auto& F = ls.features();
  const int nf = static_cast<int>(F.size()), outer = nf;
  // distances within this are refined to third order (Feature::distance): the widths that matter
  const double refine = 2 * R.threshold;
  const double tol = 1.5 * R.spacing;

  // a feature's distance (refined within `refine`) and its normal ∇φ/|∇φ|; a B-spline's from
  // the curve the level set built once for this design
  const auto distance = [&](int f, const Vec2& x, double refine_within) {
    const Feature& Ff = F[static_cast<size_t>(f)];
    if (Ff.type() == Feature::Type::kBSpline) return ls.feature_distance(f, x, v, nullptr);
    return Ff.distance<double>(x, v.theta[static_cast<size_t>(f)].data(), refine_within);
  };
  const auto gradient = [&](int f, const Vec2& x, double& gx, double& gy) {
    const Feature& Ff = F[static_cast<size_t>(f)];
    if (Ff.type() == Feature::Type::kBSpline) {
      const auto foot = v.curves[static_cast<size_t>(f)].closest(x);
      gx = foot.normal.x(), gy = foot.normal.y();
      return;
    }
    double phi;
    Ff.phi_grad<double>(x.x(), x.y(), v.theta[static_cast<size_t>(f)].data(), phi, gx, gy);
  };
  std::map<std::pair<int, int>, NarrowPart> ligaments;
  std::vector<std::vector<Vec2>> inside(static_cast<size_t>(nf));  // grid points in each hole
  std::vector<Near> near(static_cast<size_t>(nf + 1));
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) {
      if (!g.inside[static_cast<size_t>(g.index(i, j))]) continue;
      const Vec2 x = g.point(i, j);
      const double D = ls.evaluate(x, v, nullptr);
      if (D <= 0) {  // void: the holes it is in (their depth below, from their polygons)
        for (int f = 0; f < nf; ++f)
          if (F[static_cast<size_t>(f)].hole() && distance(f, x, 0) < 0)
            inside[static_cast<size_t>(f)].push_back(x);
        continue;
      }
      int m = 0;  // the boundaries near x that bound void there
      for (int f = 0; f < nf; ++f) {
        const Feature& Ff = F[static_cast<size_t>(f)];
        const double d = distance(f, x, refine);
        if (std::abs(d) > R.threshold * 4) continue;  // far: no narrow part with it here
        double gx, gy;
        gradient(f, x, gx, gy);
        const double gn = std::hypot(gx, gy);
        if (!(gn > 0)) continue;
        // ∇φ points into φ > 0; a solid feature's distance is of −φ
        Vec2 n = Vec2(gx, gy) / gn;
        if (!Ff.hole()) n = -n;
        const Vec2 foot = x - d * n;
        if (std::abs(ls.evaluate(foot, v, nullptr)) > tol || !g.covers(foot)) continue;
        near[static_cast<size_t>(m++)] = {f, std::abs(d), d > 0 ? Vec2(-n) : n};
      }
      Vec2 dir;
      const double de = edge_distance(x, edges, dir);
      near[static_cast<size_t>(m++)] = {outer, de, dir};
      std::partial_sort(near.begin(), near.begin() + std::min(m, 2), near.begin() + m,
                        [](const Near& a, const Near& b) { return a.r < b.r; });
      if (m < 2) continue;
      const Near &a = near[0], &b = near[1];
      if (b.r - a.r > tol || a.dir.dot(b.dir) > kOppositeCos) continue;
      const auto key = std::make_pair(std::min(a.entity, b.entity), std::max(a.entity, b.entity));
      const double w = a.r + b.r;
      auto it = ligaments.find(key);
      if (it == ligaments.end() || w < it->second.width) {
        NarrowPart p;
        p.first = key.first == outer ? "outer edge" : F[static_cast<size_t>(key.first)].name();
        p.second = key.second == outer ? "outer edge" : F[static_cast<size_t>(key.second)].name();
        p.width = w;
        p.at = x;
        ligaments[key] = p;
      }
    }
  for (auto& [k, p] : ligaments) R.parts.push_back(p);
  // a hole's width: the diameter of the largest disc inside it, the distance to its boundary
  // polygon (1024 points: its chords lie within 5e-6 of the radius of a circle) maximized over
  // the grid, then by a pattern search of halving steps from the deepest grid point (the level
  // set's distance estimate is no distance deep inside a super-ellipse, where ∇φ vanishes)
  for (int f = 0; f < nf; ++f) {
    if (inside[static_cast<size_t>(f)].empty()) continue;
    const Feature& Ff = F[static_cast<size_t>(f)];
    const double* th = v.theta[static_cast<size_t>(f)].data();
    const auto P = boundary_polygon(Ff, th, 1024);
    NarrowPart p;
    p.kind = NarrowPart::Kind::kHole;
    p.first = Ff.name();
    double depth = -1;
    for (const Vec2& x : inside[static_cast<size_t>(f)])
      if (const double d = polygon_distance(x, P); d > depth) depth = d, p.at = x;
    for (double step = R.spacing / 2; step > 1e-6 * R.spacing; step /= 2)
      for (bool moved = true; moved;) {
        moved = false;
        for (const Vec2& d : {Vec2(step, 0), Vec2(-step, 0), Vec2(0, step), Vec2(0, -step)}) {
          const Vec2 y = p.at + d;
          if (!g.covers(y) || distance(f, y, 0) >= 0) continue;
          if (const double dy = polygon_distance(y, P); dy > depth)
            depth = dy, p.at = y, moved = true;
        }
      }
    p.width = 2 * depth;
    R.parts.push_back(p);
  }
  for (NarrowPart& p : R.parts) p.threshold = R.threshold, p.unresolved = p.width < R.threshold;
  std::stable_sort(R.parts.begin(), R.parts.end(),
                   [](const NarrowPart& a, const NarrowPart& b) { return a.width < b.width; });

  // connected pieces of material (4-neighbours, by a stack fill) on a grid 4× finer: material
  // joined by a flange narrower than its spacing (h/16) counts as cut
  const SampleGrid fine = make_sample_grid(mesh, R.spacing / 4);
  std::vector<char> solid(fine.inside.size(), 0);
  for (int j = 0; j < fine.ny; ++j)
    for (int i = 0; i < fine.nx; ++i) {
      const size_t k = static_cast<size_t>(fine.index(i, j));
      solid[k] = fine.inside[k] && ls.evaluate(fine.point(i, j), v, nullptr) > 0;
    }
  R.piece_spacing = fine.s;
  std::vector<int> label(solid.size(), -1), stack;
  const double cell = fine.s * fine.s;
  for (size_t s = 0; s < solid.size(); ++s) {
    if (!solid[s] || label[s] >= 0) continue;
    const int id = static_cast<int>(R.pieces.size());
    R.pieces.push_back(0);
    stack.assign(1, static_cast<int>(s));
    label[s] = id;
    while (!stack.empty()) {
      const int q = stack.back();
      stack.pop_back();
      R.pieces.back() += cell;
      const int i = q % fine.nx, j = q / fine.nx;
      const int nb[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
      for (const auto& c : nb) {
        if (c[0] < 0 || c[1] < 0 || c[0] >= fine.nx || c[1] >= fine.ny) continue;
        const size_t r = static_cast<size_t>(fine.index(c[0], c[1]));
        if (solid[r] && label[r] < 0) label[r] = id, stack.push_back(static_cast<int>(r));
      }
    }
  }
  // a few grid points cut off by the sampling of a thin ligament are not a piece: at least one
  // element's area
  const double least = R.element_size * R.element_size;
  R.pieces.erase(
      std::remove_if(R.pieces.begin(), R.pieces.end(), [&](double a) { return a < least; }),
      R.pieces.end());
  std::sort(R.pieces.rbegin(), R.pieces.rend());
  return R;
}

}  // namespace lsmbs
