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
}

LevelSet::Values LevelSet::values(const Vec& p) const {
  Values v;
  for (const auto& f : features_) v.theta.push_back(f.values(p));
  return v;
}

double LevelSet::evaluate(const Vec2& x, const Values& v, double* grad) const {
  if (grad) std::fill(grad, grad + nv_, 0.0);
  return eval_node(root_, x, v, grad);
}

bool LevelSet::tie_at(const Vec2& x, const Values& v, double tol) const {
  std::vector<double> grad(static_cast<size_t>(std::max(nv_, 1)));
  bool tie = false;
  eval_node(root_, x, v, grad.data(), &tol, &tie);
  return tie;
}

double LevelSet::eval_node(const LevelSetNode& n, const Vec2& x, const Values& v, double* grad,
                           const double* tie_tol, bool* tie) const {
  switch (n.op) {
    case LevelSetNode::Op::kFeature: {
      const Feature& f = features_[n.feature];
      const auto& th = v.theta[n.feature];
      if (!grad) return f.distance<double>(x, th.data(), refine_within_, foot_iterations_);
      Dual t[kMaxFeatureParams];
      for (size_t i = 0; i < th.size(); ++i) t[i] = Dual::variable(th[i], static_cast<int>(i));
      const Dual D = f.distance<Dual>(x, t, refine_within_, foot_iterations_);
      for (size_t i = 0; i < th.size(); ++i) {
        const auto& b = f.params()[i];
        if (b.variable >= 0) grad[b.variable] += D.d[i] * b.scale;
      }
      return D.v;
    }
    case LevelSetNode::Op::kNot: {
      const double d = eval_node(n.children[0], x, v, grad, tie_tol, tie);
      if (grad)
        for (int k = 0; k < nv_; ++k) grad[k] = -grad[k];
      return -d;
    }
    case LevelSetNode::Op::kAnd:
    case LevelSetNode::Op::kOr: {
      const double sign = n.op == LevelSetNode::Op::kAnd ? 1.0 : -1.0;  // OR = −AND(−D)
      const size_t m = n.children.size();
      std::vector<double> d(m);
      std::vector<std::vector<double>> g(grad ? m : 0, std::vector<double>(nv_));
      for (size_t i = 0; i < m; ++i)
        d[i] = sign * eval_node(n.children[i], x, v, grad ? g[i].data() : nullptr, tie_tol, tie);
      const size_t imin = static_cast<size_t>(std::min_element(d.begin(), d.end()) - d.begin());
      if (tie && grad && n.ks <= 0)
        for (size_t i = 0; i < m; ++i) {
          if (i == imin || d[i] - d[imin] > *tie_tol) continue;
          double diff = 0, size = 0;
          for (int k = 0; k < nv_; ++k) {
            diff = std::max(diff, std::abs(g[i][k] - g[imin][k]));
            size = std::max({size, std::abs(g[i][k]), std::abs(g[imin][k])});
          }
          if (diff > 1e-9 * size) *tie = true;
        }
      double out = d[imin];
      if (n.ks > 0) {
        double s = 0;
        std::vector<double> w(m);
        for (size_t i = 0; i < m; ++i) s += (w[i] = std::exp(-n.ks * (d[i] - d[imin])));
        out = d[imin] - std::log(s) / n.ks;
        if (grad)
          for (size_t i = 0; i < m; ++i)
            for (int k = 0; k < nv_; ++k) grad[k] += w[i] / s * g[i][k];  // g carry sign below
      } else if (grad) {
        for (int k = 0; k < nv_; ++k) grad[k] = g[imin][k];
      }
      // g[i] are derivatives of the children's (unsigned) values; d[i] = sign · child.
      // ∂(sign·out)/∂p = Σ w_i ∂child_i/∂p, so the sign cancels: out_signed = sign·out.
      return sign * out;
    }
  }
  return 0;
}

}  // namespace lsmbs
