#pragma once
// The Boolean combination of level-set features (constructive solid geometry, §2.2), shared by
// the planar (LevelSet) and the spatial (LevelSet3) level sets: a tree of AND = min, OR = max,
// NOT = −D over the features' signed distances, optionally KS-smoothed (level_set.hpp). The
// features themselves are a callback, so that the same tree evaluates in 2D and in 3D.
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace lsmbs {

struct LevelSetNode {
  enum class Op { kFeature, kAnd, kOr, kNot } op = Op::kFeature;
  int feature = -1;
  double ks = 0;  ///< 0: exact min / max; > 0: KS smoothing parameter [1/m]
  std::vector<LevelSetNode> children;
  /// The paper's default region: material where every one of n features is positive (eq. 4).
  static LevelSetNode all_of(int n) {
    LevelSetNode root;
    root.op = Op::kAnd;
    for (int i = 0; i < n; ++i) {
      LevelSetNode leaf;
      leaf.feature = i;
      root.children.push_back(leaf);
    }
    return root;
  }
};

/// ∂D/∂p as (variable, value) entries; a variable may appear more than once (the entries sum).
using LevelSetGradient = std::vector<std::pair<int, double>>;

/// Whether two sparse gradients differ by more than 1e-9 of their largest entry.
bool gradients_differ(const LevelSetGradient& a, const LevelSetGradient& b, int nv);

/// The value of the tree `n` with the leaves' values leaf(feature, grad) (grad: null, or the
/// list the leaf appends its ∂D/∂p to). The derivatives are those of the active child of an
/// exact min/max, or the KS-weighted sum of the children's. With tie_tol and tie given, *tie is
/// set where an exact min/max has a second child within tie_tol whose derivative differs (a kink).
template <class Leaf>
double evaluate_csg(const LevelSetNode& n, const Leaf& leaf, LevelSetGradient* grad, int nv,
                    const double* tie_tol = nullptr, bool* tie = nullptr) {
  switch (n.op) {
    case LevelSetNode::Op::kFeature:
      return leaf(n.feature, grad);
    case LevelSetNode::Op::kNot: {
      const size_t from = grad ? grad->size() : 0;
      const double d = evaluate_csg(n.children[0], leaf, grad, nv, tie_tol, tie);
      if (grad)
        for (size_t k = from; k < grad->size(); ++k) (*grad)[k].second = -(*grad)[k].second;
      return -d;
    }
    case LevelSetNode::Op::kAnd:
    case LevelSetNode::Op::kOr: {
      // the children's values first; derivatives only of the active child (exact min/max) or
      // of the children with a weight (KS)
      const double sign = n.op == LevelSetNode::Op::kAnd ? 1.0 : -1.0;  // OR = −AND(−D)
      const size_t m = n.children.size();
      double dmin = std::numeric_limits<double>::infinity();
      size_t imin = 0;
      for (size_t i = 0; i < m; ++i) {
        const double d = sign * evaluate_csg(n.children[i], leaf, nullptr, nv, tie_tol, tie);
        if (d < dmin) dmin = d, imin = i;
      }
      if (n.ks <= 0) {
        if (grad) evaluate_csg(n.children[imin], leaf, grad, nv, tie_tol, tie);
        if (tie && grad) {  // a second child as low with another derivative: a kink
          LevelSetGradient gi, gmin;
          evaluate_csg(n.children[imin], leaf, &gmin, nv);
          for (size_t i = 0; i < m && !*tie; ++i) {
            if (i == imin) continue;
            gi.clear();
            const double d = sign * evaluate_csg(n.children[i], leaf, &gi, nv);
            if (d - dmin <= *tie_tol && gradients_differ(gi, gmin, nv)) *tie = true;
          }
        }
        return sign * dmin;
      }
      // KSmin(D) = m − (1/ks) ln Σ exp(−ks (D_i − m)); ∂/∂p = Σ w_i/s ∂D_i/∂p. The children's
      // derivatives are of their unsigned values, d_i = sign · child: the sign cancels
      double s = 0;
      for (size_t i = 0; i < m; ++i) {
        const double d = sign * evaluate_csg(n.children[i], leaf, nullptr, nv);
        s += std::exp(-n.ks * (d - dmin));
      }
      if (grad)
        for (size_t i = 0; i < m; ++i) {
          const size_t from = grad->size();
          const double d = sign * evaluate_csg(n.children[i], leaf, grad, nv, tie_tol, tie);
          const double w = std::exp(-n.ks * (d - dmin)) / s;
          for (size_t k = from; k < grad->size(); ++k) (*grad)[k].second *= w;
        }
      return sign * (dmin - std::log(s) / n.ks);
    }
  }
  return 0;
}

}  // namespace lsmbs
