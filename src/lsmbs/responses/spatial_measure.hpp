#pragma once
// Measures of spatial rigid bodies in natural coordinates (mbs/spatial.hpp). A body point
// x = r + Σ_k d_k e_k and a body vector u = Σ_k u_k e_k are linear in q, so positions,
// velocities and body axes have constant partials; the angular velocity is bilinear in (q, q̇):
// in the body frame Ω₁ = e₃·ė₂, Ω₂ = e₁·ė₃, Ω₃ = e₂·ė₁ (RᵀṘ = [Ω]ₓ), in the ground frame
// ω = R Ω = ½ Σ_k e_k × ė_k (exact on an orthonormal frame; both forms agree there).
// The joint angle of a revolute or cylindrical joint is an unknown of its own (AngleMeasure and
// AngularVelocityMeasure read it); the translation of a prismatic or cylindrical joint,
// a₃·(x_B − x_A), is the value of its joint equation (JointTranslationMeasure).
#include "lsmbs/mbs/spatial_joint.hpp"
#include "lsmbs/responses/measure.hpp"

namespace lsmbs {

/// Position or velocity of the body point at principal-frame offset d (x, y, z components).
class SpatialPointMeasure : public Measure {
 public:
  enum class Kind { kPosition, kVelocity };
  SpatialPointMeasure(std::string name, Kind kind, int dof0, const Vec3& d);
  std::vector<std::string> components() const override;
  std::vector<std::string> units() const override;
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  Kind kind_;
  int dof0_;
  Vec3 d_;
};

/// The mean position of nodes of a solid body (their first unknowns x, y, z at dofs[i] … + 2):
/// linear in q, constant partials 1/n.
class NodeSetMeasure : public Measure {
 public:
  NodeSetMeasure(std::string name, std::vector<int> node_dofs);
  std::vector<std::string> components() const override;
  std::vector<std::string> units() const override { return {"m", "m", "m"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  std::vector<int> dofs_;
};

/// A point of a spatial rigid body at principal-frame offset d (x = r + Σ d_k e_k, linear in
/// q), or a fixed ground point d (dof0 < 0).
struct SpatialPoint {
  int dof0 = -1;
  Vec3 d = Vec3::Zero();
  Vec3 position(const Vec& q) const;
};

/// |x_b − x_a| minus `reference` (0 for a distance, the distance at t = 0 for an elongation)
/// between two points of rigid bodies or the ground; ∂/∂q = ±u·∂x/∂q, u the unit direction.
class SpatialDistanceMeasure : public Measure {
 public:
  SpatialDistanceMeasure(std::string name, SpatialPoint a, SpatialPoint b, double reference)
      : Measure(std::move(name)), a_(a), b_(b), ref_(reference) {}
  std::vector<std::string> units() const override { return {"m"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  SpatialPoint a_, b_;
  double ref_;
};

/// The distance between the mean positions of two node sets of solid bodies, x̄_b − x̄_a, minus
/// `reference` (their distance at t = 0 for an elongation): a solid part's stretch between two
/// faces, the 3D counterpart of the planar elongation (eq. 42).
class NodeSetDistanceMeasure : public Measure {
 public:
  NodeSetDistanceMeasure(std::string name, std::vector<int> a_dofs, std::vector<int> b_dofs,
                         double reference);
  std::vector<std::string> units() const override { return {"m"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  Vec3 span(const Vec& q) const;
  std::vector<int> a_, b_;
  double ref_;
};

/// A body-fixed direction u (principal-frame components) in ground components: the body's
/// orientation as the images of chosen axes (a unit u stays unit up to the frame constraints).
class BodyAxisMeasure : public Measure {
 public:
  BodyAxisMeasure(std::string name, int dof0, const Vec3& u);
  std::vector<std::string> components() const override;
  std::vector<std::string> units() const override { return {"1", "1", "1"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  int dof0_;
  Vec3 u_;
};

/// Angular velocity of a body, in the ground frame (ω = ½ Σ e_k × ė_k) or the body's principal
/// frame (Ω₁ = e₃·ė₂, Ω₂ = e₁·ė₃, Ω₃ = e₂·ė₁).
class SpatialAngularVelocityMeasure : public Measure {
 public:
  SpatialAngularVelocityMeasure(std::string name, int dof0, bool body_frame);
  std::vector<std::string> components() const override;
  std::vector<std::string> units() const override { return {"rad/s", "rad/s", "rad/s"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  int dof0_;
  bool body_;
};

/// The translation a₃·(x_B − x_A) of a prismatic or cylindrical joint from assembly (m).
class JointTranslationMeasure : public Measure {
 public:
  /// `block`: the joint's translation as a one-equation SpatialJointBlock (its value s = Φ).
  JointTranslationMeasure(std::string name, std::unique_ptr<ConstraintElement> block);
  std::vector<std::string> units() const override { return {"m"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  LocalVec gather(const Vec& q) const;
  std::unique_ptr<ConstraintElement> block_;
};

}  // namespace lsmbs
