#include "lsmbs/geometry/length_scale.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "lsmbs/geometry/sampling.hpp"

namespace lsmbs {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The super-ellipse quadrant (a cos^(2/ξ) t, b sin^(2/η) t), t ∈ [0, π/2], and 128 points of it.
struct QuarterArc {
  static constexpr int kPoints = 128;
  double a, b, xi, eta;
  std::array<Vec2, kPoints + 1> table;
  QuarterArc(double a_, double b_, double xi_, double eta_) : a(a_), b(b_), xi(xi_), eta(eta_) {
    for (int k = 0; k <= kPoints; ++k) table[static_cast<size_t>(k)] = at(k * step());
  }
  static double step() { return 0.5 * std::numbers::pi / kPoints; }
  Vec2 at(double t) const {
    return Vec2(a * std::pow(std::cos(t), 2 / xi), b * std::pow(std::sin(t), 2 / eta));
  }
  // Closest point to y ≥ 0 (componentwise): the nearest tabulated point, then a golden-section
  // search for the least squared distance between its neighbours (the distance exact to
  // round-off, the foot to ~1e-10 of the semi-axes).
  Vec2 foot(const Vec2& y) const {
    int best = 0;
    double bd = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= kPoints; ++k) {
      const double d = (table[static_cast<size_t>(k)] - y).squaredNorm();
      if (d < bd) bd = d, best = k;
    }
    double lo = std::max(0, best - 1) * step(), hi = std::min(kPoints, best + 1) * step();
    const double r = 0.5 * (std::sqrt(5.0) - 1);
    double t1 = hi - r * (hi - lo), t2 = lo + r * (hi - lo);
    double f1 = (at(t1) - y).squaredNorm(), f2 = (at(t2) - y).squaredNorm();
    for (int it = 0; it < 48; ++it) {
      if (f1 < f2) {
        hi = t2, t2 = t1, f2 = f1;
        t1 = hi - r * (hi - lo), f1 = (at(t1) - y).squaredNorm();
      } else {
        lo = t1, t1 = t2, f1 = f2;
        t2 = lo + r * (hi - lo), f2 = (at(t2) - y).squaredNorm();
      }
    }
    return at(0.5 * (lo + hi));
  }
};

// The exact signed distance from x to the shape of feature f (> 0 outside the closed curve,
// whether the feature is a hole or a solid) at parameter values th. With T = Dual its
// derivatives by the envelope theorem: ∂s/∂θ = (∂φ/∂θ)(y*) / |∇φ(y*)| at the closest point y*.
template <class T>
T shape_distance(const Feature& f, const Vec2& x, const T* th, const QuarterArc* arc) {
  if (f.type() != Feature::Type::kSuperEllipse) {  // exact already (eq. 41; a circle)
    const T D = f.distance<T>(x, th);
    return f.hole() ? D : -D;
  }
  const double a = value(th[2]), b = value(th[3]), xi = value(th[4]), eta = value(th[5]);
  const double ang = value(th[6]), c = std::cos(ang), sn = std::sin(ang);
  const double dx = x.x() - value(th[0]), dy = x.y() - value(th[1]);
  const double u = c * dx + sn * dy, v = c * dy - sn * dx;
  std::optional<QuarterArc> own;  // tabulated only when the caller has no table of this design
  if (!arc) own.emplace(a, b, xi, eta);
  Vec2 foot = (arc ? *arc : *own).foot(Vec2(std::abs(u), std::abs(v)));
  foot = Vec2(std::copysign(foot.x(), u), std::copysign(foot.y(), v));
  const bool inside = std::pow(std::abs(u / a), xi) + std::pow(std::abs(v / b), eta) < 1;
  const double dist = (Vec2(u, v) - foot).norm();
  const T yx(value(th[0]) + c * foot.x() - sn * foot.y());
  const T yy(value(th[1]) + sn * foot.x() + c * foot.y());
  T phi, gx, gy;
  f.phi_grad(yx, yy, th, phi, gx, gy);
  const double g = std::hypot(value(gx), value(gy));
  return T(inside ? -dist : dist) + (phi - T(value(phi))) / g;
}

QuarterArc arc_of(const Feature& f, const std::vector<double>& th) {
  return f.type() == Feature::Type::kSuperEllipse ? QuarterArc(th[2], th[3], th[4], th[5])
                                                  : QuarterArc(0, 0, 1, 1);
}

// Centre of a disc that holds the feature's shape: (cx, cy), or a B-spline's control points'
// mean (the curve lies in their convex hull).
Vec2 centre(const Feature& f, const std::vector<double>& th) {
  if (f.type() != Feature::Type::kBSpline) return {th[0], th[1]};
  Vec2 c = Vec2::Zero();
  for (size_t i = 0; i + 1 < th.size(); i += 2) c += Vec2(th[i], th[i + 1]);
  return c / static_cast<double>(th.size() / 2);
}

// Radius of that disc.
double reach(const Feature& f, const std::vector<double>& th) {
  switch (f.type()) {
    case Feature::Type::kCircle:
      return th[2];
    case Feature::Type::kEllipse:
      return th[4] * std::max(th[2], th[3]);
    case Feature::Type::kSuperEllipse:
      return std::hypot(th[2], th[3]);
    case Feature::Type::kBSpline: {
      const Vec2 c = centre(f, th);
      double r = 0;
      for (size_t i = 0; i + 1 < th.size(); i += 2)
        r = std::max(r, (Vec2(th[i], th[i + 1]) - c).norm());
      return r;
    }
  }
  return kInf;
}

// KS lower envelope of the values v_k: m − (1/ρ) ln Σ exp(−ρ (v_k − m)) and each sample's weight.
double ks_min(const std::vector<double>& v, double rho, std::vector<double>& w) {
  const double m = *std::min_element(v.begin(), v.end());
  w.resize(v.size());
  double sum = 0;
  for (size_t k = 0; k < v.size(); ++k) sum += w[k] = std::exp(-rho * (v[k] - m));
  for (double& x : w) x /= sum;
  return m - std::log(sum) / rho;
}

// A feature's width, twice its inscribed radius (−s at its centre): 2r (circle), the KS minimum
// of 2ad and 2bd (ellipse, eq. 41) or of 2a and 2b (super-ellipse with ξ, η ≥ 2, eq. 43), with
// ρ = ln 2/(tolerance · δ).
LengthScaleConstraint member_size(const Feature& f, const std::vector<double>& th, double delta,
                                  double tolerance, int nv) {
  LengthScaleConstraint c;
  c.kind = "member", c.first = f.name(), c.bound = delta;
  c.gradient = Vec::Zero(nv);
  c.at = Vec2(th[0], th[1]);
  auto add = [&](int m, double dv) {  // ∂c/∂θ_m = dv
    const ParamBinding& b = f.params()[static_cast<size_t>(m)];
    if (b.variable >= 0) c.gradient[b.variable] += dv * b.scale;
  };
  if (f.type() == Feature::Type::kCircle) {
    c.value = 2 * th[2];
    add(2, 2);
    return c;
  }
  const double d = f.type() == Feature::Type::kEllipse ? th[4] : 1.0;
  const std::vector<double> v = {2 * th[2] * d, 2 * th[3] * d};
  std::vector<double> w;
  const double rho = std::log(2.0) / (tolerance * delta);
  c.value = ks_min(v, rho, w);
  c.error_bound = tolerance * delta;
  add(2, 2 * d * w[0]);
  add(3, 2 * d * w[1]);
  if (f.type() == Feature::Type::kEllipse) add(4, 2 * th[2] * w[0] + 2 * th[3] * w[1]);
  return c;
}

}  // namespace

std::string LengthScaleOptions::validate() const {
  for (const auto& [name, v] : {std::pair{"min_ligament", min_ligament},
                                {"min_edge", min_edge},
                                {"min_member", min_member},
                                {"no_cut", no_cut}})
    if (!(v >= 0) || !std::isfinite(v))
      return std::string(name) + ": expected a non-negative length [m] (0: off)";
  if (!(tolerance > 0 && tolerance < 1)) return "tolerance: expected a fraction in (0, 1)";
  if (!(spacing >= 0) || !std::isfinite(spacing))
    return "spacing: expected a non-negative length [m] (0: a quarter element)";
  return {};
}

std::string LengthScaleConstraint::name() const {
  return kind + "." + first + (second.empty() ? "" : "." + second);
}

LengthScale::LengthScale(const Mesh2D& mesh, const LevelSet& ls, int num_design,
                         LengthScaleOptions o)
    : ls_(&ls), nd_(num_design), o_(o) {
  spacing_ = o.spacing > 0 ? o.spacing : median_element_size(mesh) / 4;
  const SampleGrid g = make_sample_grid(mesh, spacing_);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i)
      if (g.inside[static_cast<size_t>(g.index(i, j))]) grid_.push_back({g.point(i, j), -1});
  int loop_index = 0;
  for (const auto& loop : mesh.boundary_loops()) {
    for (size_t k = 0; k < loop.size(); ++k) {
      const Vec2 a = mesh.nodes[static_cast<size_t>(loop[k])];
      const Vec2 b = mesh.nodes[static_cast<size_t>(loop[(k + 1) % loop.size()])];
      const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / spacing_)));
      for (int s = 0; s < n; ++s) boundary_.push_back({a + (b - a) * (double(s) / n), loop_index});
    }
    ++loop_index;
  }
}

std::vector<std::string> LengthScale::names() const {
  std::vector<std::string> n;
  const auto& F = ls_->features();
  for (int i = 0; i < nd_; ++i) {
    if (!F[static_cast<size_t>(i)].hole()) continue;
    if (o_.min_ligament > 0)
      for (int j = i + 1; j < static_cast<int>(F.size()); ++j)
        if (j >= nd_ || F[static_cast<size_t>(j)].hole())
          n.push_back("ligament." + F[static_cast<size_t>(i)].name() + "." +
                      F[static_cast<size_t>(j)].name());
    if (o_.min_edge > 0) n.push_back("edge." + F[static_cast<size_t>(i)].name());
    if (o_.no_cut > 0) n.push_back("no_cut." + F[static_cast<size_t>(i)].name());
  }
  if (o_.min_member > 0)
    for (int i = 0; i < nd_; ++i) n.push_back("member." + F[static_cast<size_t>(i)].name());
  return n;
}

std::vector<LengthScaleConstraint> LengthScale::evaluate(const Vec& p) const {
  const auto& F = ls_->features();
  const int nf = static_cast<int>(F.size());
  const LevelSet::Values V = ls_->values(p);
  const double cap = 3 * std::max({o_.min_ligament, o_.min_edge, o_.no_cut});
  std::vector<QuarterArc> arcs;  // each feature's tabulated curve at p, once per evaluation
  for (int i = 0; i < nf; ++i)
    arcs.push_back(arc_of(F[static_cast<size_t>(i)], V.theta[static_cast<size_t>(i)]));
  // a B-spline's exact distance from its shape (positive outside it) and its sparse ∂/∂p
  // (LevelSet::feature_distance: > 0 in material, the curve's own closest point)
  auto bspline_shape_distance = [&](int i, const Vec2& x, LevelSet::Gradient* g) {
    const double sign = F[static_cast<size_t>(i)].hole() ? 1.0 : -1.0;
    const double d = ls_->feature_distance(i, x, V, g);
    if (g)
      for (auto& e : *g) e.second *= sign;
    return sign * d;
  };
  // s_i at every sample within `cap` of feature i's disc (+∞ beyond: no constraint needs it)
  auto distances = [&](const std::vector<Sample>& S) {
    std::vector<std::vector<double>> d(static_cast<size_t>(nf));
    for (int i = 0; i < nf; ++i) {
      const auto& th = V.theta[static_cast<size_t>(i)];
      const Vec2 c = centre(F[static_cast<size_t>(i)], th);
      const double R = reach(F[static_cast<size_t>(i)], th);
      auto& di = d[static_cast<size_t>(i)];
      di.assign(S.size(), kInf);
      if (cap <= 0) continue;
      const Feature& f = F[static_cast<size_t>(i)];
      const QuarterArc& arc = arcs[static_cast<size_t>(i)];
      const bool curve = f.type() == Feature::Type::kBSpline;
      for (size_t k = 0; k < S.size(); ++k)
        if ((S[k].x - c).norm() - R < cap)
          di[k] = curve ? bspline_shape_distance(i, S[k].x, nullptr)
                        : shape_distance<double>(f, S[k].x, th.data(), &arc);
    }
    return d;
  };
  const std::vector<Sample> none;
  const auto dg = distances(o_.min_ligament > 0 ? grid_ : none);
  const auto db = distances(o_.min_edge > 0 || o_.no_cut > 0 ? boundary_ : none);
  // ∂s_i(x)/∂p
  auto gradient = [&](int i, const Vec2& x, double weight, Vec& grad) {
    const Feature& f = F[static_cast<size_t>(i)];
    const auto& th = V.theta[static_cast<size_t>(i)];
    if (f.type() == Feature::Type::kBSpline) {
      LevelSet::Gradient g;
      bspline_shape_distance(i, x, &g);
      for (const auto& [k, dk] : g) grad[k] += weight * dk;
      return;
    }
    std::array<Dual, kMaxFeatureParams> t;
    for (size_t m = 0; m < th.size(); ++m) t[m] = Dual::variable(th[m], static_cast<int>(m));
    const Dual s = shape_distance<Dual>(f, x, t.data(), &arcs[static_cast<size_t>(i)]);
    for (size_t m = 0; m < th.size(); ++m) {
      const ParamBinding& b = f.params()[m];
      if (b.variable >= 0) grad[b.variable] += weight * s.d[m] * b.scale;
    }
  };
  std::vector<LengthScaleConstraint> out;
  // the KS minimum of Σ_{i∈idx} s_i over the samples `use` of S (distances d), bounded by δ
  auto aggregate = [&](const std::string& kind, int i, int j, double delta,
                       const std::vector<Sample>& S, const std::vector<std::vector<double>>& d,
                       const std::vector<char>& use) {
    LengthScaleConstraint c;
    c.kind = kind, c.bound = delta;
    c.first = F[static_cast<size_t>(i)].name();
    if (j >= 0) c.second = F[static_cast<size_t>(j)].name();
    c.gradient = Vec::Zero(p.size());
    const double rho =
        std::log(static_cast<double>(std::max<size_t>(2, S.size()))) / (o_.tolerance * delta);
    c.error_bound = o_.tolerance * delta;
    std::vector<double> v;
    std::vector<size_t> at;
    for (size_t k = 0; k < S.size(); ++k) {
      if (!use.empty() && !use[k]) continue;
      const double x = d[static_cast<size_t>(i)][k] + (j >= 0 ? d[static_cast<size_t>(j)][k] : 0);
      if (x < cap) v.push_back(x), at.push_back(k);
    }
    if (v.empty()) {  // nothing within reach: the bound holds with room, flat there
      c.value = cap;
      c.at = centre(F[static_cast<size_t>(i)], V.theta[static_cast<size_t>(i)]);
      out.push_back(std::move(c));
      return;
    }
    std::vector<double> w;
    c.value = ks_min(v, rho, w);
    const size_t kmin = static_cast<size_t>(std::min_element(v.begin(), v.end()) - v.begin());
    c.at = S[at[kmin]].x;
    for (size_t q = 0; q < v.size(); ++q) {
      if (w[q] < 1e-16) continue;
      gradient(i, S[at[q]].x, w[q], c.gradient);
      if (j >= 0) gradient(j, S[at[q]].x, w[q], c.gradient);
    }
    if (c.value > cap) c.value = cap, c.gradient.setZero();
    out.push_back(std::move(c));
  };
  for (int i = 0; i < nd_; ++i) {
    if (!F[static_cast<size_t>(i)].hole()) continue;
    if (o_.min_ligament > 0)
      for (int j = i + 1; j < nf; ++j)
        if (j >= nd_ || F[static_cast<size_t>(j)].hole())
          aggregate("ligament", i, j, o_.min_ligament, grid_, dg, {});
    if (o_.min_edge > 0) aggregate("edge", i, -1, o_.min_edge, boundary_, db, {});
    if (o_.no_cut > 0) {
      // the feature's nearest approach to the boundary (a notch, or the nearer ligament) is the
      // basin of the deepest sample: the samples of its loop where the distance rises
      // monotonically away from it. The rest of the boundary keeps at least δ.
      const auto& di = db[static_cast<size_t>(i)];
      std::vector<char> use(boundary_.size(), 1);
      const size_t k0 = static_cast<size_t>(std::min_element(di.begin(), di.end()) - di.begin());
      const int loop = boundary_[k0].loop;
      size_t first = 0;  // the loop's samples [first, last)
      while (boundary_[first].loop != loop) ++first;
      size_t last = first;
      while (last < boundary_.size() && boundary_[last].loop == loop) ++last;
      const long n = static_cast<long>(last - first), c0 = static_cast<long>(k0 - first);
      auto at = [&](long k) { return first + static_cast<size_t>(((k % n) + n) % n); };
      use[k0] = 0;
      for (const long dir : {1L, -1L})
        for (long s = 1; s < n && di[at(c0 + dir * s)] >= di[at(c0 + dir * (s - 1))]; ++s)
          use[at(c0 + dir * s)] = 0;
      aggregate("no_cut", i, -1, o_.no_cut, boundary_, db, use);
    }
  }
  if (o_.min_member > 0)
    for (int i = 0; i < nd_; ++i)
      out.push_back(member_size(F[static_cast<size_t>(i)], V.theta[static_cast<size_t>(i)],
                                o_.min_member, o_.tolerance, static_cast<int>(p.size())));
  return out;
}

}  // namespace lsmbs
