#pragma once
// Model — a planar flexible multibody system as pure functions of (t, q, q̇, q̈, λ, params)
// (DESIGN.md §Core interfaces 2). It numbers the DOFs, owns the force and constraint
// elements, and assembles into a sparsity pattern computed once in finalize():
//
//   residual   R = [ r ; kΦ ],  r = M q̈ − g + Φ_qᵀ (kλ + ζΦ)                        (eq. 7)
//   iteration  S = [ c_a M + c_v C_t + c_q K_t   kΦ_qᵀ ; kΦ_q  0 ]                   (eq. 20)
//              with K_t including ζ Φ_qᵀΦ_q + Σ_i (kλ+ζΦ)_i ∂²Φ_i/∂q² (exact tangent).
//
// The unknown vector of the Newton iteration is [q; λ] (n = nq + nc); λ is the scaled
// multiplier, the physical constraint force is kλ.
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "lsmbs/linalg/sparsity.hpp"
#include "lsmbs/mbs/constraints.hpp"
#include "lsmbs/mbs/elements.hpp"
#include "lsmbs/mbs/flexible_body.hpp"
#include "lsmbs/mbs/forces.hpp"
#include "lsmbs/mbs/solid_body.hpp"

namespace lsmbs {

/// A direction in parameter space: dμ_e of material fields and d(value) of scalar parameters
/// (e.g. ∂(ModelParams)/∂p_i of one design variable).
struct ParamDirection {
  struct FieldEntry {
    int field, element;
    double value;
  };
  std::vector<FieldEntry> fields;
  std::vector<std::pair<int, double>> scalars;
  bool empty() const { return fields.empty() && scalars.empty(); }
};

/// params += t · direction
void add_direction(ModelParams& params, const ParamDirection& d, double t);

struct RigidBody {
  std::string name;
  int dof0 = -1;
  int mass_param = -1, inertia_param = -1;
  Vec2 com_offset = Vec2::Zero();
  Vec2 position0 = Vec2::Zero();  ///< reference point at t = 0
  double angle0 = 0;
  /// Body-frame points where joints, rigid connections, drivers and forces attach, in the order
  /// they were added, without repeats. Only pictures read them (io/output.hpp: the outline a
  /// rigid body is drawn with); the dynamics never do.
  std::vector<Vec2> attachments;
};

/// A spatial rigid body in natural coordinates (mbs/spatial.hpp): its centre of mass r and the
/// unit vectors of its principal frame at dof0 … dof0 + 11, q_b = [r; e1; e2; e3].
struct SpatialRigidBody {
  std::string name;
  int dof0 = -1;
  int mass_param = -1;
  std::array<int, 3> inertia_params = {-1, -1, -1};  ///< principal moments I₁, I₂, I₃
  Vec3 position0 = Vec3::Zero();                     ///< centre of mass at t = 0
  Mat3 orientation0 = Mat3::Identity();              ///< principal axes at t = 0 (columns)
  /// Principal-frame points where joints, forces and springs attach, in the order they were
  /// added, without repeats; only pictures read them (io/output.hpp).
  std::vector<Vec3> attachments;
};

/// A state at one time: positions, velocities, accelerations q̈ and scaled multipliers λ.
struct State {
  double t = 0;
  Vec q, v, a, lambda;
};

class Model {
 public:
  Model() = default;
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;

  // ------------------------------------------------------------ construction
  /// Registers a named scalar parameter; names are unique.
  int add_parameter(const std::string& name, double value);
  int parameter_index(const std::string& name) const;  ///< −1 if unknown
  const std::vector<std::string>& parameter_names() const { return param_names_; }
  int add_field(Vec values);
  int add_dofs(int n, const std::string& owner);
  RigidBody& add_rigid_body(RigidBody b);
  /// Records that something attaches to a rigid body at p (RigidBody::attachments); other kinds of
  /// points are ignored.
  void add_attachment(const PointRef& p);
  FlexibleBody& add_flexible_body(FlexibleBody b);  ///< allocates DOFs, builds element geometry
  void add_force(std::unique_ptr<ForceElement> f);
  void add_constraint(std::unique_ptr<ConstraintElement> c);
  /// Builds the sparsity pattern; no elements may be added afterwards.
  void finalize();
  bool finalized() const { return finalized_; }

  // ------------------------------------------------------------ sizes and access
  int nq() const { return nq_; }
  int nc() const { return nc_; }
  int n() const { return nq_ + nc_; }
  const ModelParams& params() const { return params_; }
  ModelParams& params() { return params_; }
  const std::vector<RigidBody>& rigid_bodies() const { return rigid_; }
  /// Allocates the body's 12 unknowns and places it (q at t = 0); its elements are added by the
  /// caller (ModelBuilder::spatial_body).
  SpatialRigidBody& add_spatial_body(SpatialRigidBody b);
  const std::vector<SpatialRigidBody>& spatial_bodies() const { return spatial_; }
  const SpatialRigidBody* find_spatial(const std::string& name) const;
  /// Records that something attaches to the spatial body with first unknown dof0 at the
  /// principal-frame point d (SpatialRigidBody::attachments).
  void add_spatial_attachment(int dof0, const Vec3& d);
  const std::vector<std::unique_ptr<FlexibleBody>>& flexible_bodies() const { return flex_; }
  /// Allocates the solid body's 3 unknowns per node at their mesh positions, builds its elements
  /// (throws lsmbs::Error naming an inverted one) and adds one SolidForce per element.
  SolidBody& add_solid_body(SolidBody b);
  const std::vector<std::unique_ptr<SolidBody>>& solid_bodies() const { return solid_; }
  const SolidBody* find_solid(const std::string& name) const;
  const RigidBody* find_rigid(const std::string& name) const;
  const FlexibleBody* find_flexible(const std::string& name) const;
  const std::vector<std::unique_ptr<ForceElement>>& forces() const { return forces_; }
  const std::vector<std::unique_ptr<ConstraintElement>>& constraints() const { return cons_; }
  int constraint_offset(int c) const { return eq_offset_[c]; }
  const BlockAssembler& assembler() const { return asm_; }
  const CscPattern& pattern() const { return asm_.pattern(); }
  /// Initial positions (placement of all bodies at t = 0) and zero velocities.
  Vec initial_positions() const { return q_init_; }
  /// Human-readable owner of a DOF or of a constraint row (for failure messages).
  std::string describe_unknown(int i) const;
  /// Why unknown i has a zero pivot in the leading matrix [M Φ_qᵀ; Φ_q 0]: "has no mass and is
  /// not fixed by a constraint", or for a spatial body's axis, its principal moments.
  std::string why_no_pivot(int i, const ModelParams& p) const;
  /// Length scale of the model (largest body size / joint distance), for tolerances.
  double length_scale() const { return length_scale_; }

  // ------------------------------------------------------------ evaluation (pure)
  /// R = [r; kΦ] (size n). If r_abs is given (size nq, caller-owned workspace), it receives
  /// Σ|terms| per row of r: a force scale for relative convergence tests.
  void residual(const State& s, const ModelParams& p, double k, double zeta, Vec& R,
                Vec* r_abs = nullptr) const;
  /// Values of S(c) on pattern() (size nnz), see the header comment.
  void iteration_matrix(const State& s, const ModelParams& p, const Coefficients& c, double k,
                        double zeta, std::vector<double>& values) const;
  /// Φ(q, t) (size nc).
  void constraints(double t, const Vec& q, const ModelParams& p, Vec& phi) const;
  /// Φ_q as a sparse nc × nq matrix (initialization, tests).
  SpMat constraint_jacobian(double t, const Vec& q, const ModelParams& p) const;
  /// Φ_t (velocity level: Φ_q q̇ + Φ_t = 0) and the acceleration bias γ with
  /// Φ̈ = Φ_q q̈ + γ,  γ_i = q̇ᵀ ∂²Φ_i/∂q² q̇ + Φ_i,tt.
  void constraint_time_terms(double t, const Vec& q, const Vec& v, const ModelParams& p, Vec& phi_t,
                             Vec& gamma) const;
  /// out = M Qdd + C Vd (nq × ncols): M = ∂r/∂q̈, C = ∂r/∂q̇ applied to blocks of vectors, one
  /// element at a time (pseudo-loads of the direct method, eq. 28).
  void mass_damping_product(const State& s, const ModelParams& p, const Mat& Qdd, const Mat& Vd,
                            Mat& out) const;
  /// ∂R/∂p along a parameter direction at fixed state (size n; the constraint rows are zero:
  /// constraints do not depend on design parameters). Only elements the direction touches are
  /// evaluated. Exact: material fields through ForceElement::field_derivative (for the planar
  /// elements eq. 3 makes r_e linear in μ_e), scalar parameters through
  /// ForceElement::param_derivative.
  void residual_param_derivative(const State& s, const ModelParams& p, const ParamDirection& d,
                                 Vec& out) const;
  /// The transposes of mass_damping_product: MtY = Mᵀ Y, CtY = Cᵀ Y (Y: nq × ncols), element
  /// by element (the discrete adjoint's backward pass, adjoint_method.cpp).
  void mass_damping_transpose_product(const State& s, const ModelParams& p, const Mat& Y, Mat& MtY,
                                      Mat& CtY) const;
  /// The adjoint contraction Yᵀ ∂R/∂p over the parameters a direction set touches: `support`
  /// lists the material-field entries (field, element) and scalar parameters, and row k of
  /// `fields` (`scalars`) receives the contraction of ∂r/∂(entry k) with the columns of Y
  /// (n × ncols, the position rows used): exact as residual_param_derivative, but once per entry
  /// for all columns, whatever the number of directions that share it.
  void residual_param_contraction(const State& s, const ModelParams& p,
                                  const ParamDirection& support, const Mat& Y, Mat& fields,
                                  Mat& scalars) const;
  /// The force element that reads entry `entry` of material field `field`, or −1.
  int force_of_field_entry(int field, int entry) const;
  /// Each element's partial derivative of its residual with respect to each entry of `support`
  /// (material-field entries first, then scalar parameters), at fixed state: fn(is_field, k,
  /// the element's dofs, ∂r_e/∂(entry k)) — the one loop behind residual_param_derivative and
  /// residual_param_contraction.
  void for_each_param_partial(
      const State& s, const ModelParams& p, const ParamDirection& support,
      const std::function<void(bool field, size_t k, std::span<const int> dofs,
                               const LocalVec& dr)>& fn) const;
  /// Residual contribution of one force element (local vector over its dofs()).
  void element_residual(int force, const State& s, const ModelParams& p, LocalVec& r) const;
  /// Ṁ w = Σ_e [∂(M_e(q) w_e)/∂q_e] q̇_e (size nq): the rate of the mass matrix along the motion
  /// applied to w. Only elements whose mass depends on q contribute (rigid bodies with an offset
  /// centre of mass); each is evaluated exactly as the difference of its tangents at q̈ = w and
  /// q̈ = 0 (r is linear in q̈). The adjoint of M(q) v̇ needs it (d/dt(Mᵀξ), idas_ggl.cpp).
  void mass_rate_product(const State& s, const ModelParams& p, const Vec& w, Vec& out) const;
  /// M_e q̈ + C_e q̇ of one force element for global vectors qdd, vd (local result).
  void element_mass_damping_product(int force, const State& s, const ModelParams& p, const Vec& qdd,
                                    const Vec& vd, LocalVec& out) const;
  /// Force elements a parameter direction touches (sorted).
  std::vector<int> forces_touched_by(const ParamDirection& dir) const;
  /// The times in (t0, t1), sorted and distinct, where a driver's prescribed acceleration jumps
  /// (and with it q̈ and λ): a variable-step integrator stops and restarts there. Loads are left
  /// out: every load law is continuous, so the accelerations are too.
  std::vector<double> time_kinks(double t0, double t1) const;
  /// Jx = Φ_q x (size nc) and Jty = Φ_qᵀ y (size nq), constraint by constraint (no matrix).
  void constraint_jacobian_products(double t, const Vec& q, const ModelParams& p, const Vec& x,
                                    const Vec& y, Vec& Jx, Vec& Jty) const;
  /// out = (Σ_i w_i ∂²Φ_i/∂q²) X (nq × cols), constraint by constraint (no matrix).
  void constraint_hessian_product(double t, const Vec& q, const Vec& w, const Mat& X,
                                  Mat& out) const;
  /// out = ∂(Φ_q q̇)/∂q X (nc × cols), constraint by constraint (no matrix).
  void velocity_constraint_jacobian_product(double t, const Vec& q, const Vec& v, const Mat& X,
                                            Mat& out) const;
  /// out = (∂(Φ_q q̇)/∂q)ᵀ Y (nq × cols; Y: nc × cols), constraint by constraint (no matrix).
  void velocity_constraint_jacobian_transpose_product(double t, const Vec& q, const Vec& v,
                                                      const Mat& Y, Mat& out) const;
  /// Σ_i w_i ∂²Φ_i/∂q² (nq × nq) with the full local pattern of every constraint (explicit zeros
  /// kept, so the pattern does not change between calls).
  SpMat constraint_hessian(double t, const Vec& q, const Vec& w) const;
  /// ∂(Φ_q q̇)/∂q (nc × nq): row i is (∂²Φ_i/∂q² q̇)ᵀ, full local pattern kept.
  SpMat velocity_constraint_jacobian(double t, const Vec& q, const Vec& v) const;
  /// The flexible element with the smallest det F at its integration points
  /// (PlaneElement::min_det_F) and the one with the smallest det F at a corner
  /// (PlaneElement::min_corner_det_F), among the elements with μ_e > kVoidMaterial: a void element
  /// of a level-set hole (ersatz material) may be squeezed through itself without consequence for
  /// the structure. det_F = +inf and body = null for a model without such elements. det_F ≤ 0 is an
  /// inverted (reflected) element: a stress-free spurious state of the St Venant–Kirchhoff
  /// material, which the integrators reject; a corner det F ≤ 0 alone is a folded element (a mesh
  /// too coarse for the deformation, or a far solution), which they report.
  static constexpr double kVoidMaterial = 0.1;
  struct Inversion {
    double det_F = INFINITY, mu = 1;
    const FlexibleBody* body = nullptr;
    int element = -1;
    double corner_det_F = INFINITY, corner_mu = 1;
    const FlexibleBody* corner_body = nullptr;
    int corner_element = -1;
    bool inverted() const { return !(det_F > 0); }
    bool folded() const { return !(corner_det_F > 0); }
    std::string describe() const;  ///< "flexible body 'b', element 7 (det F = -0.99, μ_e = 1)"
    std::string describe_fold() const;  ///< the same for the corner
  };
  Inversion most_compressed_element(const Vec& q, const ModelParams& p) const;
  /// Kinetic energy ½ q̇ᵀ M q̇ (M from the force elements).
  double kinetic_energy(const State& s, const ModelParams& p) const;
  /// Strain energy of all flexible bodies.
  double strain_energy(const Vec& q, const ModelParams& p) const;

 private:
  std::vector<std::string> param_names_;
  ModelParams params_;
  std::vector<std::string> dof_owner_;
  std::vector<RigidBody> rigid_;
  std::vector<SpatialRigidBody> spatial_;
  std::vector<std::unique_ptr<FlexibleBody>> flex_;
  std::vector<std::unique_ptr<SolidBody>> solid_;
  std::vector<std::unique_ptr<ForceElement>> forces_;
  std::vector<std::unique_ptr<ConstraintElement>> cons_;
  std::vector<int> eq_offset_, force_block_, con_block_qq_, con_block_ql_, con_block_lq_;
  std::vector<std::vector<int>> con_rows_;
  BlockAssembler asm_;
  Vec q_init_;
  int nq_ = 0, nc_ = 0;
  double length_scale_ = 1;
  bool finalized_ = false;
};

}  // namespace lsmbs
