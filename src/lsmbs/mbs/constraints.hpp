#pragma once
// Holonomic constraints Φ(q, t) = 0 used in eq. (7):
//  * PointCoincidence  p_A − p_B = 0: revolute joint (bodies or ground), rigid connection of
//                      a node to a rigid body (node keeps its body-frame offset), clamped node.
//  * Prismatic         n·(p_A − X0) = 0 (slider on a line), optionally θ_A − θ0 = 0.
//  * AngleDriver       θ_B − θ_A − s(t) = 0 (relative), or θ_B − s(t) = 0 (absolute).
//  * TranslationDriver u·(p_A − X0) − s(t) = 0.
#include <memory>
#include <vector>

#include "lsmbs/mbs/elements.hpp"
#include "lsmbs/mbs/time_law.hpp"

namespace lsmbs {

class PointCoincidence : public ConstraintElement {
 public:
  PointCoincidence(PointRef a, PointRef b);
  std::span<const int> dofs() const override { return dofs_; }
  int size() const override { return 2; }
  void evaluate(double t, const LocalVec& q, const ModelParams& p, LocalEqVec& phi,
                LocalJac* J) const override;
  void hessian(double t, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const override;

 private:
  PointRef a_, b_;
  std::vector<int> dofs_;
};

class Prismatic : public ConstraintElement {
 public:
  /// Point A slides on the line through X0 with direction u; lock_rotation fixes θ_A = θ0.
  Prismatic(PointRef a, Vec2 x0, Vec2 u, bool lock_rotation, double theta0);
  std::span<const int> dofs() const override { return dofs_; }
  int size() const override { return lock_ ? 2 : 1; }
  void evaluate(double t, const LocalVec& q, const ModelParams& p, LocalEqVec& phi,
                LocalJac* J) const override;
  void hessian(double t, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const override;
  bool angular_equation(int i) const override { return lock_ && i == 1; }  // θ_A − θ0

 private:
  PointRef a_;
  Vec2 x0_, n_;
  bool lock_;
  double theta0_;
  std::vector<int> dofs_;
};

class AngleDriver : public ConstraintElement {
 public:
  /// theta_a_dof < 0 for an absolute angle.
  AngleDriver(int theta_a_dof, int theta_b_dof, std::shared_ptr<const TimeLaw> law);
  std::span<const int> dofs() const override { return dofs_; }
  int size() const override { return 1; }
  void evaluate(double t, const LocalVec& q, const ModelParams& p, LocalEqVec& phi,
                LocalJac* J) const override;
  void hessian(double, const LocalVec&, const LocalEqVec&, LocalMat& H) const override {
    const auto n = static_cast<Eigen::Index>(dofs_.size());
    H.setZero(n, n);  // sized: H is reused across constraints of different sizes
  }
  void time_derivatives(double t, LocalEqVec& phi_t, LocalEqVec& phi_tt) const override;
  const TimeLaw& law() const { return *law_; }
  void time_kinks(double t0, double t1, std::vector<double>& out) const override {
    law_->kinks(t0, t1, out);
  }
  bool angular_equation(int) const override { return true; }

 private:
  std::vector<int> dofs_;
  std::shared_ptr<const TimeLaw> law_;
};

class TranslationDriver : public ConstraintElement {
 public:
  TranslationDriver(PointRef a, Vec2 x0, Vec2 u, std::shared_ptr<const TimeLaw> law);
  std::span<const int> dofs() const override { return dofs_; }
  int size() const override { return 1; }
  void evaluate(double t, const LocalVec& q, const ModelParams& p, LocalEqVec& phi,
                LocalJac* J) const override;
  void hessian(double t, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const override;
  void time_derivatives(double t, LocalEqVec& phi_t, LocalEqVec& phi_tt) const override;
  const TimeLaw& law() const { return *law_; }
  void time_kinks(double t0, double t1, std::vector<double>& out) const override {
    law_->kinks(t0, t1, out);
  }

 private:
  PointRef a_;
  Vec2 x0_, u_;
  std::vector<int> dofs_;
  std::shared_ptr<const TimeLaw> law_;
};

}  // namespace lsmbs
