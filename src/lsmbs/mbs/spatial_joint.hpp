#pragma once
// Joints between spatial rigid bodies in natural coordinates (mbs/spatial.hpp; García de Jalón &
// Bayo 1994, ch. 3). A body-fixed point x = r + Σ_k d_k e_k and a body-fixed vector
// u = Σ_k u_k e_k are linear in the body's coordinates q_b = [r; e1; e2; e3], so every joint
// equation below is a dot product of two such affine vectors:
//
//   Φ_i(z) = a_i(z)·b_i(z) − s_i(t),   a_i = A_i z + α_i,  b_i = B_i z + β_i,
//
// with z the joint's local coordinates (the two bodies' 12 each, or one body's against ground).
// Φ is quadratic in z with the constant Hessian A_iᵀB_i + B_iᵀA_i: exact tangents and no rotation
// parameters. The joints, with the joint frame (a1, a2, a3) on body A and (b1, b2, b3) on B,
// equal at assembly, and the point x_A on A, x_B on B, equal at assembly:
//
//   spherical    x_B − x_A = 0                                    (3)
//   universal    spherical, u_A·v_B = 0 (the cross's two axes)     (3 + 1)
//   revolute     spherical, a1·b3 = a2·b3 = 0 (axis a3)            (3 + 2)
//   cylindrical  a1·b3 = a2·b3 = 0, a1·(x_B − x_A) = a2·(x_B − x_A) = 0   (4)
//   prismatic    cylindrical, a1·b2 = 0 (no rotation about a3)     (4 + 1)
//   planar       a1·b3 = a2·b3 = 0, a3·(x_B − x_A) = 0 (normal a3) (3)
//   weld         spherical, a1·b2 = a2·b3 = a3·b1 = 0              (3 + 3)
//   inline       a1·(x_B − x_A) = a2·(x_B − x_A) = 0 (x_B on the line along a3)   (2)
//
// Each joint is one or two SpatialJointBlock constraints (a block holds at most kMaxLocalEqs
// equations). The rotation about a revolute or cylindrical axis is a joint coordinate θ (an
// extra unknown, SpatialJointAngle), so that drivers, rotational springs and measures see an
// angle that turns through any number of revolutions; the translation along a prismatic or
// cylindrical axis, s = a3·(x_B − x_A), is single-valued and is driven directly (a block
// equation with s_i(t) from a time law).
#include <array>
#include <memory>
#include <vector>

#include "lsmbs/mbs/elements.hpp"
#include "lsmbs/mbs/spatial.hpp"
#include "lsmbs/mbs/time_law.hpp"

namespace lsmbs {

/// A spatial rigid body by its first DOF (r, e1, e2, e3 at dof0 … dof0 + 11), or the ground.
struct SpatialBody {
  int dof0 = -1;
  bool ground() const { return dof0 < 0; }
  static SpatialBody ground_body() { return {}; }
};

/// A 3-vector affine in a joint's local coordinates: w(z) = A z + c.
struct SpatialAffine {
  Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxLocalDofs> A;
  Vec3 c = Vec3::Zero();
  Vec3 value(const LocalVec& z) const { return A * z + c; }
  /// w − o (both over the same local coordinates): x_B − x_A, a joint's gap.
  SpatialAffine minus(const SpatialAffine& o) const {
    SpatialAffine d = *this;
    d.A -= o.A;
    d.c -= o.c;
    return d;
  }
};

/// Joint equations a_i(z)·b_i(z) − s_i(t) = 0 between body A and body B (either may be ground).
class SpatialJointBlock : public ConstraintElement {
 public:
  SpatialJointBlock(SpatialBody a, SpatialBody b);
  /// The body-fixed point with principal-frame offset d (ground: the point d itself) of body
  /// A (side 0) or B (side 1), as an affine map of z.
  SpatialAffine point(int side, const Vec3& d) const;
  /// The body-fixed vector with principal-frame components u (ground: u itself).
  SpatialAffine vector(int side, const Vec3& u) const;
  /// A constant vector.
  SpatialAffine constant(const Vec3& c) const;
  /// Adds a·b − value = 0; `angular`: the equation constrains an angle (a dot of unit vectors),
  /// its multiplier is a moment. At most kMaxLocalEqs equations.
  void add(SpatialAffine a, SpatialAffine b, double value, bool angular);
  /// The last equation added becomes a·b − s(t) = 0 (a driver on a joint's translation).
  void drive_last(std::shared_ptr<const TimeLaw> law);

  std::span<const int> dofs() const override { return {dofs_.data(), n_}; }
  int size() const override { return static_cast<int>(eq_.size()); }
  void evaluate(double t, const LocalVec& q, const ModelParams& p, LocalEqVec& phi,
                LocalJac* J) const override;
  void hessian(double t, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const override;
  void time_derivatives(double t, LocalEqVec& phi_t, LocalEqVec& phi_tt) const override;
  void time_kinks(double t0, double t1, std::vector<double>& out) const override;
  bool angular_equation(int i) const override { return eq_[static_cast<size_t>(i)].angular; }

 private:
  struct Equation {
    SpatialAffine a, b;
    double value = 0;
    bool angular = false;
    std::shared_ptr<const TimeLaw> law;  // s(t) = value + law(t) when set
    LocalMat hessian;                    // A_aᵀA_b + A_bᵀA_a, constant
    bool zero_hessian = false;           // an equation linear in z (a constant factor)
  };
  int column(int side) const;  // first local column of side 0/1, −1 for ground
  std::array<SpatialBody, 2> body_;
  std::array<int, kMaxLocalDofs> dofs_{};
  size_t n_ = 0;
  std::vector<Equation> eq_;
};

/// The rotation θ of B relative to A about a joint axis, as a joint coordinate (one extra unknown
/// at theta_dof): with (a1, a2) ⟂ the axis on A and b1 on B, equal to a1 at assembly (θ = 0),
///   Φ = cos θ (a2·b1) − sin θ (a1·b1) = 0,   ∂Φ/∂θ = −(a1·b1 cos θ + a2·b1 sin θ) = −1 on Φ = 0
/// when the axes are aligned (b1 = cos θ a1 + sin θ a2), so θ is well defined through any number
/// of turns; drivers and rotational springs act on it as on a planar angle.
class SpatialJointAngle : public ConstraintElement {
 public:
  /// a1, a2 in A's principal frame, b1 in B's (ground: global components).
  SpatialJointAngle(SpatialBody a, SpatialBody b, const Vec3& a1, const Vec3& a2, const Vec3& b1,
                    int theta_dof);
  std::span<const int> dofs() const override { return {dofs_.data(), n_}; }
  int size() const override { return 1; }
  void evaluate(double t, const LocalVec& q, const ModelParams& p, LocalEqVec& phi,
                LocalJac* J) const override;
  void hessian(double t, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const override;
  bool angular_equation(int /*i*/) const override { return true; }

 private:
  // the frame vectors use only the e-DOFs: 9 per body, then θ
  std::array<int, 19> dofs_{};
  size_t n_ = 0;
  SpatialAffine a1_, a2_, b1_;
  int theta_col_ = 0;
};

/// A spatial joint's frame at assembly, in global components: the point where it sits and its
/// orthonormal axes (x3: the revolute/cylindrical/prismatic axis, the planar joint's normal).
struct SpatialJointFrame {
  Vec3 point = Vec3::Zero();
  Mat3 axes = Mat3::Identity();  ///< columns x1, x2, x3
  /// A right-handed frame whose third axis is `axis` (normalized), the first chosen stably.
  static SpatialJointFrame about(const Vec3& point, const Vec3& axis);
};

enum class SpatialJointKind {
  kSpherical,
  kUniversal,
  kRevolute,
  kCylindrical,
  kPrismatic,
  kPlanar,
  kWeld,
  kInline
};

/// The constraint blocks of a joint of the given kind between bodies A and B, placed at assembly
/// poses pose_a, pose_b (ignored for ground), with the frame f in global components. A universal
/// joint's cross axes are f's x1 (on A) and x2 (on B). With theta_dof ≥ 0 a revolute or
/// cylindrical joint also gets its rotation coordinate (SpatialJointAngle about x3).
std::vector<std::unique_ptr<ConstraintElement>> make_spatial_joint(
    SpatialJointKind kind, SpatialBody a, const SpatialPose& pose_a, SpatialBody b,
    const SpatialPose& pose_b, const SpatialJointFrame& f, int theta_dof = -1);

/// Whether a joint of that kind has a rotation about x3 (revolute, cylindrical) or a translation
/// along it (prismatic, cylindrical) that a driver, a spring or a measure may act on.
bool spatial_joint_rotates(SpatialJointKind kind);
bool spatial_joint_slides(SpatialJointKind kind);

/// The translation driver of a prismatic or cylindrical joint: a3·(x_B − x_A) − s(t) = 0, s
/// measured from assembly (s(0) = 0 there).
std::unique_ptr<ConstraintElement> make_spatial_translation_driver(
    SpatialBody a, const SpatialPose& pose_a, SpatialBody b, const SpatialPose& pose_b,
    const SpatialJointFrame& f, std::shared_ptr<const TimeLaw> law);

}  // namespace lsmbs
