#include "lsmbs/geometry/level_set.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lsmbs {

LevelSet::LevelSet(std::vector<Feature> features, LevelSetNode root, int nv)
    : features_(std::move(features)), root_(std::move(root)), nv_(nv) {
  for (const auto& f : features_) {
    std::vector<int> vars;
    for (const auto& b : f.params())
      if (b.variable >= 0 && std::find(vars.begin(), vars.end(), b.variable) == vars.end())
        vars.push_back(b.variable);
    feat_vars_.push_back(vars);
  }
  smoothed_.assign(features_.size(), false);
  const auto mark = [this](const LevelSetNode& n, bool under_ks, const auto& self) -> void {
    if (n.op == LevelSetNode::Op::kFeature) {
      if (n.feature >= 0 && n.feature < static_cast<int>(smoothed_.size()) && under_ks)
        smoothed_[static_cast<size_t>(n.feature)] = true;
      return;
    }
    for (const auto& c : n.children) self(c, under_ks || n.ks > 0, self);
  };
  mark(root_, false, mark);
}

LevelSet::Values LevelSet::values(const Vec& p) const {
  Values v;
  v.curves.resize(features_.size());
  for (size_t f = 0; f < features_.size(); ++f) {
    v.theta.push_back(features_[f].values(p));
    if (features_[f].type() == Feature::Type::kBSpline)
      v.curves[f] = ClosedBSpline(v.theta[f].data(), static_cast<int>(v.theta[f].size() / 2));
  }
  return v;
}

double LevelSet::evaluate(const Vec2& x, const Values& v, Gradient* grad,
                          const double* frozen) const {
  if (grad) grad->clear();
  return eval_node(root_, x, v, grad, frozen);
}

double LevelSet::feature_distance(int fi, const Vec2& x, const Values& v, Gradient* grad) const {
  const Feature& f = features_[static_cast<size_t>(fi)];
  const auto& th = v.theta[static_cast<size_t>(fi)];
  const double sign = f.hole() ? 1.0 : -1.0;
  if (f.type() == Feature::Type::kBSpline) {
    // the exact distance and ∂D/∂P_j = −N_j(t*) n(t*) (ClosedBSpline): four control points
    const auto foot = v.curves[static_cast<size_t>(fi)].closest(x);
    if (grad) {
      std::array<int, 4> idx;
      std::array<double, 4> N;
      v.curves[static_cast<size_t>(fi)].basis(foot.t, idx, N);
      for (size_t j = 0; j < 4; ++j)
        for (int c = 0; c < 2; ++c) {
          const auto& b = f.params()[static_cast<size_t>(2 * idx[j] + c)];
          if (b.variable >= 0)
            grad->emplace_back(b.variable, -sign * N[j] * foot.normal[c] * b.scale);
        }
    }
    return sign * foot.distance;
  }
  if (!grad) return f.distance<double>(x, th.data(), refine_within_, foot_iterations_);
  Dual t[kMaxFeatureParams];
  for (size_t i = 0; i < th.size(); ++i) t[i] = Dual::variable(th[i], static_cast<int>(i));
  const Dual D = f.distance<Dual>(x, t, refine_within_, foot_iterations_);
  for (size_t i = 0; i < th.size(); ++i) {
    const auto& b = f.params()[i];
    if (b.variable >= 0) grad->emplace_back(b.variable, D.d[i] * b.scale);
  }
  return D.v;
}

bool gradients_differ(const LevelSetGradient& a, const LevelSetGradient& b, int nv) {
  std::vector<double> diff(static_cast<size_t>(nv)), size(static_cast<size_t>(nv));
  for (const auto& [k, g] : a) diff[static_cast<size_t>(k)] += g;
  for (const auto& [k, g] : b) diff[static_cast<size_t>(k)] -= g;
  double dmax = 0, smax = 0;
  for (const auto* s : {&a, &b})
    for (const auto& [k, g] : *s) smax = std::max(smax, std::abs(g));
  for (double d : diff) dmax = std::max(dmax, std::abs(d));
  return dmax > 1e-9 * smax;
}

bool LevelSet::tie_at(const Vec2& x, const Values& v, double tol) const {
  Gradient grad;
  bool tie = false;
  eval_node(root_, x, v, &grad, nullptr, &tol, &tie);
  return tie;
}

double LevelSet::eval_node(const LevelSetNode& n, const Vec2& x, const Values& v, Gradient* grad,
                           const double* frozen, const double* tie_tol, bool* tie) const {
  const auto leaf = [&](int f, Gradient* g) {
    if (frozen && !std::isnan(frozen[f])) return frozen[f];
    return feature_distance(f, x, v, g);
  };
  return evaluate_csg(n, leaf, grad, nv_, tie_tol, tie);
}

}  // namespace lsmbs
