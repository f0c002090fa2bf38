#pragma once
// Svanberg's classic method of moving asymptotes (Svanberg 1987, with the 2007 regularization
// of the approximations): one convex separable subproblem per outer iteration, solved by the
// primal-dual interior-point method of Svanberg's mmasub/subsolv. Unlike NLopt's LD_MMA (the
// globally convergent CCSA variant, which adds conservative inner iterations and scales its
// step with the gradient's size), the classic method takes one simulation per iteration and
// moves each variable within the asymptote box whatever the gradient's magnitude — the
// behaviour of the method the paper used (its iteration counts are counts of simulations).
//
// Problem, in the variables the caller chooses (lsmbs passes p scaled to [0, 1]):
//   minimize f0(x)  subject to  f_i(x) ≤ 0 (i = 1..m),  xmin ≤ x ≤ xmax,
// with the artificial variables of Svanberg's formulation (a0 = 1, a_i = 0, c_i = `c`,
// d_i = 1) so that an infeasible subproblem stays solvable.
#include "lsmbs/core/types.hpp"

namespace lsmbs {

struct MmaOptions {
  double asyinit = 0.5;  ///< initial asymptote distance, fraction of xmax − xmin
  double asyincr = 1.2;  ///< asymptote widening when a variable keeps its direction
  double asydecr = 0.7;  ///< narrowing when it oscillates
  double move = 0.5;     ///< move limit per iteration, fraction of xmax − xmin
  double albefa = 0.1;   ///< distance of the subproblem bounds from the asymptotes
  double c = 1000;       ///< penalty on the artificial variables y_i
  double raa0 = 1e-5;    ///< regularization of the approximations

  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

class MmaClassic {
 public:
  MmaClassic(Vec xmin, Vec xmax, int m, MmaOptions o = {});
  /// One MMA iteration at x (the k-th call is iteration k): f0 and its gradient, constraint
  /// values f (m) and their gradients df (m × n). Returns the next point.
  Vec step(const Vec& x, const Vec& df0, const Vec& f, const Mat& df);
  int iteration() const { return iter_; }
  const Vec& lower_asymptotes() const { return low_; }
  const Vec& upper_asymptotes() const { return upp_; }
  /// Lagrange multipliers of the last subproblem's constraints.
  const Vec& multipliers() const { return lam_; }

 private:
  Vec xmin_, xmax_;
  int m_;
  MmaOptions o_;
  int iter_ = 0;
  Vec xold1_, xold2_, low_, upp_, lam_;
};

/// The subproblem solver (Svanberg's subsolv), exposed for tests. Minimizes
///   Σ_j p0_j/(u_j − x_j) + q0_j/(x_j − l_j) + a0 z + Σ_i c_i y_i + ½ d_i y_i²
/// s.t. Σ_j P_ij/(u_j − x_j) + Q_ij/(x_j − l_j) − a_i z − y_i ≤ b_i, α ≤ x ≤ β, y, z ≥ 0.
struct MmaSubproblem {
  Vec low, upp, alpha, beta, p0, q0, a, b, c, d;
  Mat P, Q;
  double a0 = 1;
};
struct MmaSubSolution {
  Vec x, y, lam;
  double z = 0;
  int iterations = 0;
};
MmaSubSolution solve_mma_subproblem(const MmaSubproblem& s, double epsimin = 1e-7);

}  // namespace lsmbs
