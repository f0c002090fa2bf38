#pragma once
// SolidElement — one element of a 3D solid flexible body, the spatial counterpart of
// PlaneElement (fem/plane_element.hpp): total Lagrangian, St Venant–Kirchhoff material, absolute
// nodal coordinates (the unknowns are the current positions x_I of the nodes; X_I their
// reference positions). The material enters as E (the caller's μ_e E0, eq. 3) and ν; the
// consistent mass is ρ times unit_mass().
//
// Coordinates are interleaved, x = (x1, y1, z1, x2, …), 3n values for n nodes; matrices are
// column-major 3n × 3n. Implementations: HexElement and TetElement (fem/hex_element.hpp).
#include <Eigen/Dense>

#include "lsmbs/core/types.hpp"

namespace lsmbs {

class SolidElement {
 public:
  virtual ~SolidElement() = default;
  virtual int num_nodes() const = 0;
  int num_dofs() const { return 3 * num_nodes(); }

  /// f_int(x) at Young's modulus E; K = ∂f_int/∂x (material + geometric) when K is not null.
  /// f_int is the gradient of strain_energy, K its Hessian (symmetric).
  virtual void internal_force(const double* x, double E, double nu, double* f, double* K) const = 0;
  /// ∂f_int/∂ν (f_int is linear in E, which needs no function of its own).
  virtual void internal_force_nu_derivative(const double* x, double E, double nu,
                                            double* df) const = 0;
  virtual double strain_energy(const double* x, double E, double nu) const = 0;
  /// ∫ N_I N_J dV (n × n): ρ times it is the consistent mass of one direction.
  virtual Eigen::Ref<const Eigen::MatrixXd> unit_mass() const = 0;
  /// ∫ N_I dV (n): the weight's share of each node.
  virtual Eigen::Ref<const Eigen::VectorXd> shape_integrals() const = 0;
  virtual double volume() const = 0;
  /// The second Piola–Kirchhoff stress at the element centre (Voigt S11, S22, S33, S12, S23,
  /// S13), with the element's own strain there (an enhanced element: its enhanced strain).
  virtual Eigen::Matrix<double, 6, 1> centre_stress(const double* x, double E, double nu) const = 0;
  /// The deformation gradient at the element centre.
  virtual Mat3 centre_F(const double* x) const = 0;
  /// The smallest det F over the integration points and the centre (≤ 0: inverted).
  virtual double min_det_F(const double* x) const = 0;
};

/// St Venant–Kirchhoff in Voigt form: S = C E with E = (E11, E22, E33, 2E12, 2E23, 2E13) and S =
/// (S11, S22, S33, S12, S23, S13); C = λ 1⊗1 + 2μ I in those components.
Eigen::Matrix<double, 6, 6> svk_voigt(double E, double nu);
/// ∂C/∂ν at E fixed.
Eigen::Matrix<double, 6, 6> svk_voigt_nu_derivative(double E, double nu);

}  // namespace lsmbs
