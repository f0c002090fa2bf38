#include "lsmbs/geometry/length_scale.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "lsmbs/geometry/length_scale_parts.hpp"
#include "lsmbs/geometry/sampling.hpp"

namespace lsmbs {
namespace {

using namespace length_scale_parts;

constexpr double kInf = std::numeric_limits<double>::infinity();

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

std::vector<LengthScaleConstraint> LengthScaleMeasures::evaluate(const Vec& p) const {
  auto all = evaluate_all(p);
  if (left_out_.empty()) return all;
  std::vector<LengthScaleConstraint> kept;
  for (auto& c : all)
    if (std::find(left_out_.begin(), left_out_.end(), c.name()) == left_out_.end())
      kept.push_back(std::move(c));
  return kept;
}

std::vector<std::string> LengthScaleMeasures::names() const {
  std::vector<std::string> kept;
  for (auto& n : all_names())
    if (std::find(left_out_.begin(), left_out_.end(), n) == left_out_.end()) kept.push_back(n);
  return kept;
}

std::vector<std::string> LengthScaleMeasures::leave_out_overlaps(const Vec& p) {
  std::vector<std::string> out;
  for (const auto& c : evaluate(p))
    if (c.kind == "ligament" && c.value < 0) out.push_back(c.name());
  left_out_.insert(left_out_.end(), out.begin(), out.end());
  return out;
}

std::string LengthScaleConstraint::name() const {
  return kind + "." + first + (second.empty() ? "" : "." + second);
}

LengthScale::LengthScale(const Mesh2D& mesh, const LevelSet& ls, int num_design,
                         LengthScaleOptions o)
    : ls_(&ls), nd_(num_design), o_(o) {
  void_ = void_features(ls.root(), ls.features());
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

std::vector<std::string> LengthScale::all_names() const {
  return constraint_names(ls_->features(), void_, nd_, o_);
}

std::vector<LengthScaleConstraint> LengthScale::evaluate_all(const Vec& p) const {
  const auto& F = ls_->features();
  const int nf = static_cast<int>(F.size());
  const LevelSet::Values V = ls_->values(p);
  const double cap = 3 * std::max({o_.min_ligament, o_.min_edge, o_.no_cut});
  std::vector<QuarterArc> arcs;  // each feature's tabulated curve at p, once per evaluation
  for (int i = 0; i < nf; ++i)
    arcs.push_back(arc_of(F[static_cast<size_t>(i)].type(), V.theta[static_cast<size_t>(i)]));
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
    const auto m = sampled_minimum(d[static_cast<size_t>(i)],
                                   j >= 0 ? &d[static_cast<size_t>(j)] : nullptr, use, cap, rho);
    if (!m.any) {  // nothing within reach: the bound holds with room, flat there
      c.value = cap;
      c.at = centre(F[static_cast<size_t>(i)], V.theta[static_cast<size_t>(i)]);
      out.push_back(std::move(c));
      return;
    }
    c.value = m.value;
    c.at = S[m.argmin].x;
    for (const auto& [k, w] : m.weights) {
      gradient(i, S[k].x, w, c.gradient);
      if (j >= 0) gradient(j, S[k].x, w, c.gradient);
    }
    if (c.value > cap) c.value = cap, c.gradient.setZero();
    out.push_back(std::move(c));
  };
  for (int i = 0; i < nd_; ++i) {
    if (!void_[static_cast<size_t>(i)]) continue;
    if (o_.min_ligament > 0)
      for (int j = i + 1; j < nf; ++j)
        if (j >= nd_ || void_[static_cast<size_t>(j)])
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
      out.push_back(member_size(F[static_cast<size_t>(i)].name(), F[static_cast<size_t>(i)].type(),
                                F[static_cast<size_t>(i)].params(), V.theta[static_cast<size_t>(i)],
                                o_.min_member, o_.tolerance, static_cast<int>(p.size())));
  return out;
}

}  // namespace lsmbs
