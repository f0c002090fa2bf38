#pragma once
// Spatial rigid bodies in natural coordinates (García de Jalón & Bayo, "Kinematic and Dynamic
// Simulation of Multibody Systems", 1994, ch. 3 and 5): a body's coordinates are its centre of
// mass r and the three unit vectors of its principal frame, q_b = [r; e1; e2; e3] (12 numbers).
// A body-fixed point is x = r + Σ_k d_k e_k, linear in q_b, so that
//  - the mass matrix is constant: M_b = diag(m I₃, J₁ I₃, J₂ I₃, J₃ I₃) with J_k = ∫ρ d_k² dV
//    = (I_i + I_j − I_k)/2 from the principal moments (T = ½ m|ṙ|² + ½ Σ J_k |ė_k|² = ½ ΩᵀIΩ);
//  - there is no gyroscopic or centripetal term: r_b = M_b q̈_b − f_ext, linear in q̈;
//  - rigidity is six quadratic constraints (|e_k|² = 1, e_i·e_j = 0) with constant Hessians,
//    and joints on body points are linear or bilinear in q.
// The index-3 augmented-Lagrangian generalized-α of eq. (7)–(20) then integrates a spatial body
// with no rotation parameters and no singularity; every sensitivity method sees ordinary force
// and constraint elements (docs/methods.md, "Spatial rigid bodies").
#include <Eigen/Geometry>
#include <array>
#include <string>

#include "lsmbs/mbs/elements.hpp"

namespace lsmbs {

/// Inertia of a spatial rigid body in natural coordinates at dof0 … dof0 + 11 (r, e1, e2, e3):
/// mass m and principal moments I₁, I₂, I₃ about the centre of mass (scalar parameters), a
/// constant gravity g acting on the centre of mass.
class SpatialRigidInertia : public ForceElement {
 public:
  SpatialRigidInertia(int dof0, int mass_param, std::array<int, 3> inertia_params, Vec3 gravity,
                      std::string what);
  std::span<const int> dofs() const override { return dofs_; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override { return what_; }
  bool uses_parameter(int j) const override;
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;
  void mass_damping(const LocalState& s, const ModelParams& p, LocalMat& M,
                    LocalMat& C) const override;
  /// J_k = (I_i + I_j − I_k)/2 for the principal moments I (the second moments ∫ρ d_k² dV).
  static Vec3 second_moments(const Vec3& I);

 private:
  Vec3 second_moments(const ModelParams& p) const;  ///< from the moments' parameters
  std::array<int, 12> dofs_;
  int m_;
  std::array<int, 3> I_;
  Vec3 g_;
  std::string what_;
};

/// Rigidity of a spatial body's frame in natural coordinates, three equations of the six
/// (the local constraint blocks hold three): kNormal: (|e_k|² − 1)/2 = 0, k = 1, 2, 3;
/// kOrthogonal: e₂·e₃, e₃·e₁, e₁·e₂ = 0. Both are dimensionless (angles, for the multipliers'
/// units: ConstraintElement::angular_equation).
class SpatialFrameConstraint : public ConstraintElement {
 public:
  enum class Kind { kNormal, kOrthogonal };
  SpatialFrameConstraint(int dof0, Kind kind);
  std::span<const int> dofs() const override { return dofs_; }
  int size() const override { return 3; }
  void evaluate(double t, const LocalVec& q, const ModelParams& p, LocalEqVec& phi,
                LocalJac* J) const override;
  void hessian(double t, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const override;
  bool angular_equation(int /*i*/) const override { return true; }

 private:
  std::array<int, 9> dofs_;  // e1, e2, e3
  Kind kind_;
};

/// Spherical joint between a body point d (principal frame, from the centre of mass) and a
/// ground point p₀: Φ = r + Σ_k d_k e_k − p₀ = 0, linear in q (zero Hessian).
class SpatialGroundSpherical : public ConstraintElement {
 public:
  SpatialGroundSpherical(int dof0, Vec3 body_point, Vec3 ground_point);
  std::span<const int> dofs() const override { return dofs_; }
  int size() const override { return 3; }
  void evaluate(double t, const LocalVec& q, const ModelParams& p, LocalEqVec& phi,
                LocalJac* J) const override;
  void hessian(double /*t*/, const LocalVec& /*q*/, const LocalEqVec& /*w*/,
               LocalMat& H) const override {
    H.setZero(12, 12);
  }

 private:
  std::array<int, 12> dofs_;
  Vec3 d_, p0_;
};

/// Natural coordinates of a body: centre of mass and rotation matrix R = [e1 e2 e3].
struct SpatialPose {
  Vec3 r;
  Mat3 R;
  /// q_b = [r; e1; e2; e3] written to q[dof0 …]; with Ω (body angular velocity) and ṙ, also
  /// q̇_b = [ṙ; R[Ω]ₓ] to v[dof0 …].
  void write(int dof0, Vec& q) const;
  static void write_rates(int dof0, const Mat3& R, const Vec3& rdot, const Vec3& Omega, Vec& v);
  static SpatialPose read(int dof0, const Vec& q);
  /// Ω = vee(Rᵀ Ṙ) from natural coordinates and their rates (exact when R is orthonormal).
  static Vec3 body_angular_velocity(int dof0, const Vec& q, const Vec& v);
};

}  // namespace lsmbs
