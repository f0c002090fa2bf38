#pragma once
// Loads and spring–dampers on spatial rigid bodies in natural coordinates (mbs/spatial.hpp).
// A body point x = r + Σ_k d_k e_k is linear in q_b, so a force F at it has the generalized
// force Q_r = F, Q_{e_k} = d_k F. A torque T has Q_{e_k} = ½ T × e_k: with ė_k = ω × e_k its
// power is Σ_k Q_k·ė_k = ½ Σ_k [(T·ω)|e_k|² − (T·e_k)(e_k·ω)] = T·ω on an orthonormal frame.
// A load given in the body frame (F = Σ_j f_j e_j) turns with the body and enters K_t.
#include <array>
#include <memory>
#include <string>

#include "lsmbs/mbs/spatial_joint.hpp"

namespace lsmbs {

/// A force at a body point, or a torque on the body, scale · (L₁(t), L₂(t), L₃(t)) in the ground
/// frame or the body's principal frame; a null law is zero.
class SpatialLoad : public ForceElement {
 public:
  enum class Kind { kForce, kTorque };
  enum class Frame { kGround, kBody };
  SpatialLoad(int dof0, Kind kind, Frame frame, const Vec3& body_point,
              std::array<std::shared_ptr<const TimeLaw>, 3> laws, int scale_param,
              std::string what);
  std::span<const int> dofs() const override { return dofs_; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override { return what_; }
  bool uses_parameter(int j) const override { return j == scale_; }
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;

 private:
  void add(const LocalState& s, double scale, LocalVec& r, double cq, LocalMat* S) const;
  std::array<int, 12> dofs_{};
  Kind kind_;
  Frame frame_;
  Vec3 d_;
  std::array<std::shared_ptr<const TimeLaw>, 3> laws_;
  int scale_;
  std::string what_;
};

/// Point-to-point spring–damper between two spatial body points (either may be on ground):
/// tension T = k (l − l0) + c l̇ pulls them together. The points are linear in q, so
/// ∂²l/∂q² = Dᵀ (I − n nᵀ) D / l with D = ∂(x_B − x_A)/∂q constant.
class SpatialSpringDamper : public ForceElement {
 public:
  /// c_param < 0: no damper.
  SpatialSpringDamper(SpatialBody a, const Vec3& da, SpatialBody b, const Vec3& db, int k_param,
                      int c_param, int free_length_param, std::string what);
  std::span<const int> dofs() const override { return block_.dofs(); }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override { return what_; }
  bool uses_parameter(int j) const override { return j == k_ || j == c_ || j == l0_; }
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;
  /// The distance between the two points at q (global coordinates).
  double length(const Vec& q) const;

 private:
  SpatialJointBlock block_;  // the two bodies' DOFs and the affine maps of their points
  SpatialAffine gap_;        // x_B − x_A
  int k_, c_, l0_;
  std::string what_;
};

}  // namespace lsmbs
