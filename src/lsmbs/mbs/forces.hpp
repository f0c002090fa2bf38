#pragma once
// Force elements (inertia, springs, applied loads) of the residual of eq. (7):
//  r = M(q) q̈ + f_gyr(q, q̇) + f_int(q, q̇) − f_ext(q, q̇, t).
// Scalar properties are read from ModelParams::scalars through parameter indices, so that any
// of them can be bound to a design variable.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "lsmbs/mbs/elements.hpp"
#include "lsmbs/mbs/table.hpp"
#include "lsmbs/mbs/time_law.hpp"

namespace lsmbs {

/// Rigid-body inertia about a reference point (x, y, θ): mass m at body-frame offset c, rotary
/// inertia J_c about the centre of mass. With c ≠ 0 the mass matrix depends on θ and a
/// centripetal term −m θ̇² R c appears. A point mass on a body is this element with J_c = 0.
class RigidInertia : public ForceElement {
 public:
  RigidInertia(int dof0, int mass_param, int inertia_param, Vec2 offset, std::string what);
  std::span<const int> dofs() const override { return dofs_; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override { return what_; }
  bool uses_parameter(int j) const override { return j == m_ || j == J_; }
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;
  bool mass_depends_on_q() const override { return c_.squaredNorm() > 0; }
  bool linear_in_rates() const override { return false; }

 private:
  std::array<int, 3> dofs_;
  int m_, J_;  // parameter indices (J_ < 0: none)
  Vec2 c_;
  std::string what_;
};

/// Point mass on a node (constant diagonal mass and weight).
class NodeMass : public ForceElement {
 public:
  NodeMass(int dof0, int mass_param, std::string what)
      : dofs_{dof0, dof0 + 1}, m_(mass_param), what_(std::move(what)) {}
  std::span<const int> dofs() const override { return dofs_; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override { return what_; }
  bool uses_parameter(int j) const override { return j == m_; }
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;

 private:
  std::array<int, 2> dofs_;
  int m_;
  std::string what_;
};

/// Point-to-point spring–damper: tension T = k (l − l0) + c l̇ (positive pulls A and B together).
class SpringDamper : public ForceElement {
 public:
  SpringDamper(PointRef a, PointRef b, int k_param, int c_param, int l0_param, std::string what);
  std::span<const int> dofs() const override { return dofs_; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override { return what_; }
  bool uses_parameter(int j) const override { return j == k_ || j == c_ || j == l0_; }
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;

 private:
  PointRef a_, b_;
  std::vector<int> dofs_;
  int k_, c_, l0_;
  std::string what_;
};

/// Force F(t) = (Fx(t), Fy(t)) fixed in the inertial frame, applied at a point; each component
/// a time law (constant or tabulated) scaled by a parameter.
class PointForce : public ForceElement {
 public:
  PointForce(PointRef a, std::shared_ptr<const TimeLaw> fx, std::shared_ptr<const TimeLaw> fy,
             int scale_param, std::string what);
  std::span<const int> dofs() const override { return dofs_; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override { return what_; }
  bool uses_parameter(int j) const override { return j == scale_; }
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;

 private:
  PointRef a_;
  std::vector<int> dofs_;
  std::shared_ptr<const TimeLaw> fx_, fy_;
  int scale_;
  std::string what_;
};

/// Pressure P(s) × area along a fixed unit direction u, applied at a point. The argument s is
/// the time, or the angle θ of a named rigid body (plus offset; the table may be periodic,
/// e.g. 4π for a four-stroke cycle) — then the load depends on q and enters K_t.
class PressureForce : public ForceElement {
 public:
  PressureForce(PointRef a, Vec2 u, int area_param, Table1D table, int angle_dof, double offset,
                std::string what);
  std::span<const int> dofs() const override { return dofs_; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override { return what_; }
  bool uses_parameter(int j) const override { return j == area_; }
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;
  /// Pressure at the given state (for outputs).
  double pressure(double t, double angle) const;

 private:
  PointRef a_;
  Vec2 u_;
  int area_;
  Table1D table_;
  int angle_dof_;  // < 0: pressure vs time
  double offset_;
  std::vector<int> dofs_;
  std::string what_;
};

/// Torque T(t) on a rigid body, a time law (constant or tabulated) scaled by a parameter: a
/// generalized force on the body's angle DOF, r_θ −= scale · T(t) (eq. 7: f_ext enters with a
/// minus sign). The torque does not depend on the state: no tangent.
class Torque : public ForceElement {
 public:
  Torque(int theta_dof, std::shared_ptr<const TimeLaw> law, int scale_param, std::string what);
  std::span<const int> dofs() const override { return dofs_; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override { return what_; }
  bool uses_parameter(int j) const override { return j == scale_; }
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;

 private:
  std::array<int, 1> dofs_;
  std::shared_ptr<const TimeLaw> law_;
  int scale_;
  std::string what_;
};

/// Rotational spring–damper between the angles of two rigid bodies a and b (b may be ground,
/// θ_b ≡ 0): moment M = k (θa − θb − θ0) + c (θ̇a − θ̇b), acting on a with −M and on b with +M,
/// so that it resists the relative rotation. Residual (eq. 7, internal force): r_a += M,
/// r_b −= M; K_t = k [1 −1; −1 1], C_t = c [1 −1; −1 1].
class RotationalSpringDamper : public ForceElement {
 public:
  /// theta_b < 0: b is the ground.
  RotationalSpringDamper(int theta_a, int theta_b, int k_param, int c_param, int free_angle_param,
                         std::string what);
  std::span<const int> dofs() const override { return dofs_; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override { return what_; }
  bool uses_parameter(int j) const override { return j == k_ || j == c_ || j == th0_; }
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;

 private:
  std::vector<int> dofs_;  // θa [, θb]
  int k_, c_, th0_;
  std::string what_;
};

}  // namespace lsmbs
