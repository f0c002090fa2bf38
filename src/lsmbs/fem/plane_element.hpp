#pragma once
// PlaneElement — one element of a plane-stress flexible body: total Lagrangian, St Venant–
// Kirchhoff material, absolute nodal coordinates (the unknowns are the current positions x_I of
// the nodes; X_I their reference positions). In the spirit of TACS' TACSElement: the element
// carries its own kernels, and the flexible body, the model, the stress measure and the outputs
// know no element type. The material enters as E (the caller's μ_e E0, eq. 3), ν and the
// thickness t; the consistent mass is ρ t times unit_mass().
//
// Coordinates are interleaved, x = (x1, y1, x2, y2, …), 2n values for n nodes; matrices are
// column-major 2n × 2n. Implementations: QuadElement (fem/quad_element.hpp), TriElement
// (fem/tri_element.hpp); each is registered once in fem/element_types.cpp.
#include <Eigen/Dense>

#include "lsmbs/core/types.hpp"

namespace lsmbs {

/// Options of an element's construction, as a case sets them ("integration").
struct ElementOptions {
  /// Every strain term with the full Gauss rule (a Q4 then locks in bending); the default is the
  /// element's own remedy (the Q4's one-point shear).
  bool full_integration = false;
};

/// Von Mises value of the Cauchy stress at a point and its derivatives with respect to the
/// element's 2n node coordinates (stress recovery).
struct PointStress {
  double vm = 0;
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 18, 1> dvm;
};

class PlaneElement {
 public:
  virtual ~PlaneElement() = default;
  virtual int num_nodes() const = 0;
  int num_dofs() const { return 2 * num_nodes(); }

  /// f_int(x) at Young's modulus E; K = ∂f_int/∂x (material + geometric) when K is not null.
  virtual void internal_force(const double* x, double E, double nu, double t, double* f,
                              double* K) const = 0;
  /// ∂f_int/∂ν (f_int is linear in E and t, which need no function of their own).
  virtual void internal_force_nu_derivative(const double* x, double E, double nu, double t,
                                            double* df) const = 0;
  virtual double strain_energy(const double* x, double E, double nu, double t) const = 0;
  /// ∫ N_I N_J dA (n × n): ρ t times it is the consistent mass of one direction.
  virtual Eigen::Ref<const Eigen::MatrixXd> unit_mass() const = 0;
  /// ∫ N_I dA (n): the weight's share of each node.
  virtual Eigen::Ref<const Eigen::VectorXd> shape_integrals() const = 0;
  virtual double area() const = 0;

  /// Green–Lagrange strain (E11, E22, 2E12) and deformation gradient at the element centre.
  virtual void centre_strain(const double* x, Eigen::Vector3d& E, Mat2& F) const = 0;
  /// ∇_X N_I at the element centre (n × 2): where stresses are recovered.
  virtual Eigen::Ref<const Eigen::MatrixX2d> centre_gradients() const = 0;
  /// The Cauchy stress's von Mises value at the centre for the solid material (E0, ν) and, with
  /// `derivatives`, its derivatives with respect to x (exact; plane_centre_stress below).
  PointStress centre_stress(const double* x, double E0, double nu, bool derivatives) const;

  /// The smallest det F over the integration points and the centre (≤ 0: inverted; E of a
  /// reflection is that of the unreflected element, so a reflected element is stress-free).
  virtual double min_det_F(const double* x) const = 0;
  /// The smallest det F at the element's corners (≤ 0 with a positive min_det_F: folded).
  virtual double min_corner_det_F(const double* x) const = 0;
};

/// The Cauchy von Mises stress σ = F S Fᵀ / J (S = D E, plane stress, E0 and ν) from F = Σ x_I ⊗
/// ∇_X N_I (G: n × 2 gradients), and its derivatives along dF = e_i ⊗ ∇_X N_I:
///   dE = ½(dFᵀF + FᵀdF), dS = D dE, dτ = dF S Fᵀ + F dS Fᵀ + F S dFᵀ, dJ = J tr(F⁻¹ dF),
///   dσ = (dτ − σ dJ)/J, dσ_vm = ((2σ11 − σ22) dσ11 + (2σ22 − σ11) dσ22 + 6 σ12 dσ12)/(2σ_vm).
/// At σ_vm = 0 the subgradient 0 is returned.
PointStress plane_centre_stress(Eigen::Ref<const Eigen::MatrixX2d> G, const double* x, double E0,
                                double nu, bool derivatives);

}  // namespace lsmbs
