#pragma once
// Measures — named per-step quantities f_n(q, q̇, q̈, λ, p) recorded as time histories and
// aggregated into responses: a point's position, a body angle, the distance or elongation
// between two points (deformed minus undeformed distance, positive in tension, §5.2), the
// deviation of a point from a prescribed path (eq. 44), a constraint force, energies, the mass
// of a flexible body, a body's angular velocity, a point's velocity. Each provides its partial
// derivatives with respect to the state for the sensitivity tracker (eq. 24). Aggregation over
// time windows: aggregation.hpp.
#include <memory>
#include <string>
#include <vector>

#include "lsmbs/mbs/model.hpp"
#include "lsmbs/responses/aggregation.hpp"

namespace lsmbs {

/// Sparse partial derivatives of one measure component: ∂f/∂q, ∂f/∂q̇, ∂f/∂q̈, ∂f/∂λ.
struct MeasureGradient {
  std::vector<std::pair<int, double>> dq, dv, da, dl;
  void clear() { dq.clear(), dv.clear(), da.clear(), dl.clear(); }
};

class Measure {
 public:
  virtual ~Measure() = default;
  explicit Measure(std::string name) : name_(std::move(name)) {}
  const std::string& name() const { return name_; }
  /// Column names of the components (e.g. "tip.x", "tip.y"); a scalar measure has one.
  virtual std::vector<std::string> components() const { return {name_}; }
  /// SI unit of each component, in the ASCII notation of docs/case-format.md ("m", "m/s", "rad",
  /// "N*m", "J", "kg"; "1" for a dimensionless one).
  virtual std::vector<std::string> units() const = 0;
  virtual void evaluate(const Model& m, const State& s, const ModelParams& p,
                        double* out) const = 0;
  /// Partial derivatives of component c with respect to the state (eq. 24).
  virtual void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                        MeasureGradient& g) const = 0;
  /// Whether the measure depends on model parameters explicitly (∂f/∂p of eq. 24).
  virtual bool depends_on_params() const { return false; }
  /// The value does not depend on the state (q, v, a, λ, t): a mass. Such a measure is the same
  /// under every service condition (sensitivity/conditions.hpp evaluates it once).
  virtual bool state_independent() const { return false; }
  /// Exact ∂f/∂μ_e of component c for the material field `field` (one per flexible body), when
  /// the measure provides it; otherwise false, and ∂f/∂p is taken by a central difference along
  /// each parameter direction (exact for the measures linear in μ).
  virtual bool field_partials(const Model&, const State&, const ModelParams&, int /*c*/,
                              int& /*field*/, Vec& /*df_dmu*/) const {
    return false;
  }

 private:
  std::string name_;
};

/// Position of a material point.
class PositionMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"m", "m"}; }
  PositionMeasure(std::string name, PointRef pt) : Measure(std::move(name)), pt_(pt) {}
  std::vector<std::string> components() const override { return {name() + ".x", name() + ".y"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  PointRef pt_;
};

/// Angle of a rigid body.
class AngleMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"rad"}; }
  AngleMeasure(std::string name, int theta_dof) : Measure(std::move(name)), dof_(theta_dof) {}
  void evaluate(const Model&, const State& s, const ModelParams&, double* out) const override {
    *out = s.q[dof_];
  }
  void gradient(const Model&, const State&, const ModelParams&, int,
                MeasureGradient& g) const override {
    g.dq.emplace_back(dof_, 1.0);
  }

 private:
  int dof_;
};

/// Angular velocity θ̇ of a rigid body.
class AngularVelocityMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"rad/s"}; }
  AngularVelocityMeasure(std::string name, int theta_dof)
      : Measure(std::move(name)), dof_(theta_dof) {}
  void evaluate(const Model&, const State& s, const ModelParams&, double* out) const override {
    *out = s.v[dof_];
  }
  void gradient(const Model&, const State&, const ModelParams&, int,
                MeasureGradient& g) const override {
    g.dv.emplace_back(dof_, 1.0);
  }

 private:
  int dof_;
};

/// Velocity of a material point: ṗ = ∂p/∂q q̇ (a node: its velocity; a rigid-body point at
/// body-frame offset d: (ẋ, ẏ) + θ̇ R′(θ) d). ∂ṗ/∂q̇ = ∂p/∂q; ∂ṗ/∂θ = −θ̇ R(θ) d.
class VelocityMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"m/s", "m/s"}; }
  VelocityMeasure(std::string name, PointRef pt) : Measure(std::move(name)), pt_(pt) {}
  std::vector<std::string> components() const override { return {name() + ".x", name() + ".y"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  PointRef pt_;
};

/// Distance |p_B − p_A| minus `reference` (0 for a distance; the undeformed distance for an
/// elongation).
class DistanceMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"m"}; }
  DistanceMeasure(std::string name, PointRef a, PointRef b, double reference)
      : Measure(std::move(name)), a_(a), b_(b), ref_(reference) {}
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  PointRef a_, b_;
  double ref_;
};

/// Position of a point in the frame of a rigid body (deflection as seen from the body): r =
/// R(θ)ᵀ (p − o), o the frame's origin (a point of the body) and θ the body's angle. Components
/// .x, .y along the body's axes.
class FramePositionMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"m", "m"}; }
  FramePositionMeasure(std::string name, PointRef point, PointRef frame)
      : Measure(std::move(name)), pt_(point), frame_(frame) {}
  std::vector<std::string> components() const override { return {name() + ".x", name() + ".y"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  PointRef pt_, frame_;  // frame_: a point of a rigid body (PointRef::Kind::kBody)
};

/// Velocity of a point in the frame of a rigid body: ṙ, the time derivative of the
/// FramePositionMeasure, ṙ = R(θ)ᵀ (ṗ − ȯ) − θ̇ J r (J the rotation by +90°): what an observer
/// riding on the body sees. Components .x, .y along the body's axes.
class FrameVelocityMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"m/s", "m/s"}; }
  FrameVelocityMeasure(std::string name, PointRef point, PointRef frame)
      : Measure(std::move(name)), pt_(point), frame_(frame) {}
  std::vector<std::string> components() const override { return {name() + ".x", name() + ".y"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  PointRef pt_, frame_;
};

/// Signed distance of a point P from the line through A and B: ((B − A) × (P − A)) / |B − A|,
/// positive to the left of the direction A → B (a beam's deflection from its chord).
class LineDistanceMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"m"}; }
  LineDistanceMeasure(std::string name, PointRef point, PointRef a, PointRef b)
      : Measure(std::move(name)), pt_(point), a_(a), b_(b) {}
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  PointRef pt_, a_, b_;
};

/// A linear combination c0 + Σ w_i f_i of components of other measures (each given by its
/// measure and component): its partials are the same combination of theirs. A measure whose
/// explicit ∂f/∂μ is exact (stress) combines only with measures that do not depend on the
/// design's parameters, and constraint forces are not combined (their scaling belongs to the run).
class CombinationMeasure : public Measure {
 public:
  struct Term {
    const Measure* measure;
    int component;
    double weight;
  };
  CombinationMeasure(std::string name, double constant, std::vector<Term> terms, std::string unit)
      : Measure(std::move(name)),
        constant_(constant),
        terms_(std::move(terms)),
        unit_(std::move(unit)) {}
  std::vector<std::string> units() const override { return {unit_}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;
  bool depends_on_params() const override;
  bool state_independent() const override;
  bool field_partials(const Model& m, const State& s, const ModelParams& p, int c, int& field,
                      Vec& df_dmu) const override;

 private:
  double constant_;
  std::vector<Term> terms_;
  std::string unit_;
};

/// Prescribed planar path of a serial chain driven by time laws: link i has absolute angle
/// φ_i = s_i(t) (absolute driver) or φ_{i−1} + s_i(t) (relative driver); the path point is
/// origin + Σ L_i (cos φ_i, sin φ_i) — the rigid kinematics of the drivers (§6).
struct ChainPath {
  Vec2 origin = Vec2::Zero();
  struct Link {
    std::shared_ptr<const TimeLaw> law;
    bool relative = false;
    double length = 0;
  };
  std::vector<Link> links;
  Vec2 at(double t) const;
};

/// ‖q_pres(t) − p(q)‖ (eq. 44).
class PathDeviationMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"m"}; }
  PathDeviationMeasure(std::string name, PointRef pt, ChainPath path)
      : Measure(std::move(name)), pt_(pt), path_(std::move(path)) {}
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;

 private:
  PointRef pt_;
  ChainPath path_;
};

/// Constraint force kλ of one joint (all its equations): a force [N] per length equation, a
/// moment [N·m] per angle equation (`angular`, one flag per row; empty: all forces).
class ConstraintForceMeasure : public Measure {
 public:
  ConstraintForceMeasure(std::string name, std::vector<int> rows, std::vector<bool> angular = {})
      : Measure(std::move(name)), rows_(std::move(rows)), angular_(std::move(angular)) {
    angular_.resize(rows_.size(), false);
  }
  std::vector<std::string> components() const override;
  std::vector<std::string> units() const override;
  /// The forces of physical multipliers λ (a static solution, IDAS); a generalized-α state
  /// carries λ/k: evaluate_scaled.
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override {
    evaluate_scaled(m, s, p, 1.0, out);
  }
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override {
    gradient_scaled(m, s, p, c, 1.0, g);
  }
  /// With the scaling k of the run whose state it is (GeneralizedAlpha::automatic_scaling): an
  /// argument, so that two runs of one study with different k can evaluate at once.
  void evaluate_scaled(const Model&, const State& s, const ModelParams&, double k,
                       double* out) const;
  void gradient_scaled(const Model&, const State&, const ModelParams&, int c, double k,
                       MeasureGradient& g) const {
    g.dl.emplace_back(rows_[c], k);
  }

 private:
  std::vector<int> rows_;
  std::vector<bool> angular_;
};

class KineticEnergyMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"J"}; }
  using Measure::Measure;
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override {
    *out = m.kinetic_energy(s, p);
  }
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;
  bool depends_on_params() const override { return true; }
};

class StrainEnergyMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"J"}; }
  using Measure::Measure;
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override {
    *out = m.strain_energy(s.q, p);
  }
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;
  bool depends_on_params() const override { return true; }
};

/// The mass of a flexible or solid body, Σ_e μ_e ρ0 V_e: state-independent, linear in μ (its ∂/∂p
/// by a central difference along each parameter direction is exact).
template <class Body>
class BodyMassMeasure : public Measure {
 public:
  std::vector<std::string> units() const override { return {"kg"}; }
  BodyMassMeasure(std::string name, const Body* b) : Measure(std::move(name)), body_(b) {}
  void evaluate(const Model&, const State&, const ModelParams& p, double* out) const override {
    *out = body_->mass(p);
  }
  void gradient(const Model&, const State&, const ModelParams&, int,
                MeasureGradient&) const override {}
  bool depends_on_params() const override { return true; }
  bool state_independent() const override { return true; }

 private:
  const Body* body_;
};
using FlexibleMassMeasure = BodyMassMeasure<FlexibleBody>;
using SolidMassMeasure = BodyMassMeasure<SolidBody>;

/// Aggregated von Mises stress of a flexible or a solid body. For element e, the Cauchy stress
/// σ = F S Fᵀ / det F at the element centre, with S = D(E0, ν) E (the solid material's St
/// Venant–Kirchhoff stress at the element's strain; plane stress, or 3D for a solid body:
/// fem/solid_stress.hpp), its von Mises value σ_vm,e,
/// and the relaxed stress s_e = μ_e^q σ_vm,e (the qp-approach: with q < 1 a partially filled
/// element keeps a finite stress as μ_e → 0, and a void element's fictitious stress is scaled
/// down). The per-step value aggregates over the elements:
///  * ks:    f = σ_ref (m + ln Σ_e exp(ρ (s_e/σ_ref − m)) / ρ),  m = max_e s_e/σ_ref;
///           max_e s_e ≤ f ≤ max_e s_e + σ_ref ln(N)/ρ,
///  * pnorm: f = (Σ_e s_e^P)^(1/P);  max_e s_e ≤ f ≤ N^(1/P) max_e s_e,
/// and the response aggregates over time. ∂f/∂q is exact (forward-mode duals over a planar
/// element's coordinates; closed form for a solid one); ∂f/∂μ_e = (∂f/∂s_e) q μ_e^(q−1) σ_vm,e
/// exactly; at σ_vm,e = 0 (an unstrained element) the subgradient 0 is used.
class StressMeasure : public Measure {
 public:
  enum class Aggregation { kKs, kPNorm };
  struct Options {
    Aggregation aggregation = Aggregation::kKs;
    double parameter = 50;    ///< ρ (ks, dimensionless) or P (pnorm)
    double reference = 0;     ///< σ_ref [Pa] (ks normalization)
    double relaxation = 0.5;  ///< q
  };
  StressMeasure(std::string name, const FlexibleBody* body, Options o)
      : Measure(std::move(name)), body_(body), o_(o) {}
  StressMeasure(std::string name, const SolidBody* body, Options o)
      : Measure(std::move(name)), solid_(body), o_(o) {}
  std::vector<std::string> units() const override { return {"Pa"}; }
  void evaluate(const Model& m, const State& s, const ModelParams& p, double* out) const override;
  void gradient(const Model& m, const State& s, const ModelParams& p, int c,
                MeasureGradient& g) const override;
  bool depends_on_params() const override { return true; }
  bool field_partials(const Model& m, const State& s, const ModelParams& p, int c, int& field,
                      Vec& df_dmu) const override;
  /// Relaxed stresses s_e of every element (for reporting: the largest and where it sits).
  void element_stresses(const State& s, const ModelParams& p, std::vector<double>& out) const;
  /// The body measured: a flexible one (else null) or a solid one (else null).
  const FlexibleBody* flexible() const { return body_; }
  const SolidBody* solid() const { return solid_; }
  const std::string& body_name() const { return body_ ? body_->name : solid_->name; }
  /// Element e's centre in the body's frame (planar: 2 coordinates; solid: 3, at t = 0).
  std::vector<double> element_centre(int e) const;
  const Options& options() const { return o_; }

 private:
  // aggregate of s (n elements) and its weights ∂f/∂s_e
  double aggregate(const std::vector<double>& s, std::vector<double>* w) const;
  int field() const { return body_ ? body_->field : solid_->field; }
  // the solid body's element e: its node coordinates from q into x (3 per node)
  void solid_coordinates(int e, const Vec& q, double* x) const;
  const FlexibleBody* body_ = nullptr;
  const SolidBody* solid_ = nullptr;
  Options o_;
};

}  // namespace lsmbs
