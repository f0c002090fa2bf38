#pragma once
// The two kinds of local contributions a Model is made of. Both are pure: they read the
// gathered local state and the model parameters and write local vectors/matrices; the Model
// gathers and scatters through the fixed sparsity pattern.
//
//  ForceElement      r_loc = M a + f_gyr(q,v) + f_int(q,v) − f_ext(q,v,t)   (the residual of eq. 7
//                    without the constraint term), and S_loc = c_a M + c_v C_t + c_q K_t.
//  ConstraintElement Φ_loc(q,t) (m ≤ 3 equations), Φ_q, the Hessian contraction Σ_i w_i ∂²Φ_i/∂q²
//                    (for K_t and the acceleration-level constraint), and the rheonomic terms
//                    Φ_t, Φ_tt (drivers; our constraints have Φ_qt = 0).
#include <span>
#include <string>
#include <vector>

#include "lsmbs/core/types.hpp"

namespace lsmbs {

/// Values the elements read: named scalar parameters, per-element material fields (μ_e of
/// eq. 3, one vector per flexible body) and gravity. Design variables act through these.
struct ModelParams {
  std::vector<double> scalars;
  std::vector<Vec> fields;
  Vec2 gravity = Vec2::Zero();
};

struct LocalState {
  double t = 0;
  LocalVec q, v, a;
};

struct Coefficients {
  double ca = 0, cv = 0, cq = 0;
};

class ForceElement {
 public:
  virtual ~ForceElement() = default;
  /// Global DOF indices touched (≤ kMaxLocalDofs).
  virtual std::span<const int> dofs() const = 0;
  /// Adds to r (local); if S is non-null also adds c_a M + c_v C + c_q K.
  virtual void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                        const Coefficients* c, LocalMat* S) const = 0;
  /// Short description for messages ("body arm2, element 17").
  virtual std::string describe() const = 0;
  /// Whether the element reads scalar parameter j (for element-local pseudo-loads).
  virtual bool uses_parameter(int /*j*/) const { return false; }
  /// Adds ∂r/∂p_j (local) at fixed state: the exact partial derivative of the element's residual
  /// (eq. 7 without the constraint term) with respect to scalar parameter j. Nothing is added
  /// when the element does not read p_j.
  virtual void param_derivative(const LocalState& s, const ModelParams& p, int j,
                                LocalVec& dr) const = 0;
  /// The entry of a material field (μ_e of eq. 3) the element reads: field index and entry, or
  /// {-1, -1} when it reads none.
  struct MaterialEntry {
    int field = -1, entry = -1;
  };
  virtual MaterialEntry material_entry() const { return {}; }
  /// Adds ∂r/∂μ (local) for the entry material_entry() names, at fixed state.
  virtual void field_derivative(const LocalState& /*s*/, const ModelParams& /*p*/,
                                LocalVec& /*dr*/) const {}
  /// Whether ∂r/∂q̈ (the mass matrix) depends on q (rigid bodies with an offset centre of mass).
  virtual bool mass_depends_on_q() const { return false; }
  /// Whether r is linear in (q̇, q̈) at fixed q (then r(q̇ + δq̇, q̈ + δq̈) − r = M δq̈ + C δq̇
  /// exactly). False for rigid inertia (centripetal term quadratic in θ̇).
  virtual bool linear_in_rates() const { return true; }
  /// M = ∂r/∂q̈ and C = ∂r/∂q̇ (local). Default: two evaluate() calls; elements override it
  /// when their mass is cheap (quads: constant).
  virtual void mass_damping(const LocalState& s, const ModelParams& p, LocalMat& M,
                            LocalMat& C) const {
    const auto nd = static_cast<Eigen::Index>(dofs().size());
    LocalVec r = LocalVec::Zero(nd);
    M.setZero(nd, nd);
    C.setZero(nd, nd);
    const Coefficients cm{1, 0, 0}, cc{0, 1, 0};
    evaluate(s, p, r, &cm, &M);
    evaluate(s, p, r, &cc, &C);
  }
};

class ConstraintElement {
 public:
  virtual ~ConstraintElement() = default;
  virtual std::span<const int> dofs() const = 0;
  virtual int size() const = 0;
  /// Φ and (optionally) Φ_q at (t, q).
  virtual void evaluate(double t, const LocalVec& q, const ModelParams& p, LocalEqVec& phi,
                        LocalJac* J) const = 0;
  /// H = Σ_i w_i ∂²Φ_i/∂q² (zero for constraints linear in q).
  virtual void hessian(double t, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const = 0;
  /// ∂Φ/∂t and ∂²Φ/∂t² (drivers); zero by default.
  virtual void time_derivatives(double /*t*/, LocalEqVec& phi_t, LocalEqVec& phi_tt) const {
    phi_t.setZero(size());
    phi_tt.setZero(size());
  }
  /// Appends the times in (t0, t1) where the prescribed motion's acceleration jumps.
  virtual void time_kinks(double /*t0*/, double /*t1*/, std::vector<double>& /*out*/) const {}
  /// Whether equation i constrains an angle [rad]; its multiplier kλ is then a moment [N·m]. The
  /// other equations constrain lengths [m], and their multipliers are forces [N].
  virtual bool angular_equation(int /*i*/) const { return false; }
  /// Name of the joint for messages and constraint-force outputs.
  const std::string& name() const { return name_; }
  void set_name(std::string n) { name_ = std::move(n); }

 private:
  std::string name_;
};

/// A material point: fixed in ground, a node of a flexible body, or a point of a rigid body
/// at an offset d in its body frame. p = x_node, or p = x + R(θ) d.
struct PointRef {
  enum class Kind { kGround, kNode, kBody } kind = Kind::kGround;
  int dof0 = -1;              ///< first global DOF (x); body: x, y, θ at dof0..dof0+2
  Vec2 local = Vec2::Zero();  ///< ground: position; body: offset in body frame; node: unused
  int num_dofs() const { return kind == Kind::kGround ? 0 : kind == Kind::kNode ? 2 : 3; }
  void append_dofs(std::vector<int>& d) const {
    for (int i = 0; i < num_dofs(); ++i) d.push_back(dof0 + i);
  }
};

/// Kinematics of a PointRef from its local coordinates (node: x, y; body: x, y, θ).
struct PointKinematics {
  /// Position.
  static Vec2 position(const PointRef& p, const double* q);
  /// Jacobian columns written to J(:, col .. col+nd) scaled by `sign`.
  template <class MatT>
  static void jacobian(const PointRef& p, const double* q, MatT& J, int row, int col,
                       double sign = 1) {
    if (p.kind == PointRef::Kind::kGround) return;
    J(row, col) += sign;
    J(row + 1, col + 1) += sign;
    if (p.kind == PointRef::Kind::kBody) {
      const Vec2 rd = rotation_derivative(q[2]) * p.local;
      J(row, col + 2) += sign * rd.x();
      J(row + 1, col + 2) += sign * rd.y();
    }
  }
  /// Σ_a w_a ∂²p_a/∂q² (only the θθ entry of a body point is non-zero: −w·R d).
  static double hess_thetatheta(const PointRef& p, const double* q, const Vec2& w) {
    if (p.kind != PointRef::Kind::kBody) return 0;
    return -w.dot(rotation(q[2]) * p.local);
  }
};

}  // namespace lsmbs
