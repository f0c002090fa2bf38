#pragma once
// Eight-node hexahedron, total Lagrangian, St Venant–Kirchhoff, absolute nodal coordinates.
// Nodes in VTK/Gmsh order: the face ζ = −1 counter-clockwise seen from +ζ (ξ, η = (−1,−1),
// (1,−1), (1,1), (−1,1)), then the face ζ = +1 likewise.
//
// Locking remedy: enhanced assumed strains on the Green–Lagrange strain (Simo & Rifai 1990 in the
// form of Büchter, Ramm & Roehl 1994), nine parameters α:
//
//   E = E_c(x) + M(ξ) α,   M(ξ) = (j0 / j(ξ)) T0 M̃(ξ),
//   M̃: E_ξξ = ξ α1, E_ηη = η α2, E_ζζ = ζ α3, 2E_ξη = ξ α4 + η α5, 2E_ηζ = η α6 + ζ α7,
//      2E_ξζ = ξ α8 + ζ α9 (natural components), T0 their map to Cartesian ones at the centre
//      (E = J0⁻ᵀ E_nat J0⁻¹), j the Jacobian determinant.
//
// M̃ is odd in ξ, η, ζ, so ∫ M dV = 0: a homogeneous deformation gives α = 0 and the element
// passes the patch test. St Venant–Kirchhoff is linear in E and E is linear in α, so the element
// equations for α are linear and α is condensed in closed form,
//   α(x) = −H⁻¹ L(x),  H = Σ_g w j MᵀCM,  L = Σ_g w j MᵀC E_c(x),
// which makes the element an ordinary hyperelastic one: its energy W(x) = W(x, α(x)) has the
// gradient f = Σ_g w j Bᵀ S (S = C(E_c + Mα), by stationarity in α) and the symmetric Hessian
//   K = Σ_g w j (BᵀCB + K_σ(S)) − Γᵀ H⁻¹ Γ,  Γ = Σ_g w j MᵀCB,
// exact for every sensitivity method. The enhanced modes free the bending and the Poisson
// (normal) strains that the trilinear field ties together: one element through a beam's depth
// is enough (docs/methods.md, "Solid elements"). Formulation::kFull is the plain 2 × 2 × 2 Gauss
// element, which locks; it is kept for the locking study.
#include <array>

#include "lsmbs/fem/solid_element.hpp"

namespace lsmbs {

class HexElement final : public SolidElement {
 public:
  enum class Formulation { kEnhanced, kFull };
  /// X: reference node positions in the order above. Throws lsmbs::Error when det J ≤ 0 at the
  /// centre or an integration point (inverted, degenerate or badly distorted). A corner may have
  /// det J ≤ 0: MacNeal & Harder's patch has one, and the integration never sees it.
  explicit HexElement(const std::array<Vec3, 8>& X, Formulation f = Formulation::kEnhanced);
  int num_nodes() const override { return 8; }
  void internal_force(const double* x, double E, double nu, double* f, double* K) const override;
  void internal_force_nu_derivative(const double* x, double E, double nu,
                                    double* df) const override;
  double strain_energy(const double* x, double E, double nu) const override;
  Eigen::Ref<const Eigen::MatrixXd> unit_mass() const override { return unit_mass_; }
  Eigen::Ref<const Eigen::VectorXd> shape_integrals() const override { return shape_int_; }
  double volume() const override { return volume_; }
  Eigen::Matrix<double, 6, 1> centre_stress(const double* x, double E, double nu) const override;
  double min_det_F(const double* x) const override;
  Mat3 centre_F(const double* x) const override;
  /// The condensed enhanced-strain parameters α(x) (zero for kFull).
  Eigen::Matrix<double, 9, 1> enhanced_parameters(const double* x, double E, double nu) const;

 private:
  struct Point {
    Eigen::Matrix<double, 8, 3> G;  // ∇_X N_I
    double wj = 0;                  // weight × det J
    Eigen::Matrix<double, 6, 9> M;  // enhanced strain modes (zero for kFull)
  };
  struct Eval;  // one evaluation's per-point strains, B matrices and the condensation
  void evaluate(const double* x, const Eigen::Matrix<double, 6, 6>& C, Eval& ev) const;
  std::array<Point, 8> gp_;
  Eigen::Matrix<double, 8, 3> G_centre_;
  bool enhanced_;
  Eigen::MatrixXd unit_mass_;
  Eigen::VectorXd shape_int_;
  double volume_ = 0;
};

/// Four-node tetrahedron (constant strain), total Lagrangian, St Venant–Kirchhoff: one point
/// integrates it exactly. Stiff in bending; for Gmsh meshes of real parts.
///   ∫ N_I N_J dV = V/20 (1 + δ_IJ),  ∫ N_I dV = V/4.
class TetElement final : public SolidElement {
 public:
  /// X: reference node positions with (X1 − X0)·((X2 − X0) × (X3 − X0)) > 0. Throws
  /// lsmbs::Error when inverted or degenerate.
  explicit TetElement(const std::array<Vec3, 4>& X);
  int num_nodes() const override { return 4; }
  void internal_force(const double* x, double E, double nu, double* f, double* K) const override;
  void internal_force_nu_derivative(const double* x, double E, double nu,
                                    double* df) const override;
  double strain_energy(const double* x, double E, double nu) const override;
  Eigen::Ref<const Eigen::MatrixXd> unit_mass() const override { return unit_mass_; }
  Eigen::Ref<const Eigen::VectorXd> shape_integrals() const override { return shape_int_; }
  double volume() const override { return volume_; }
  Eigen::Matrix<double, 6, 1> centre_stress(const double* x, double E, double nu) const override;
  double min_det_F(const double* x) const override;
  Mat3 centre_F(const double* x) const override;

 private:
  Eigen::Matrix<double, 4, 3> G_;
  Eigen::MatrixXd unit_mass_;
  Eigen::VectorXd shape_int_;
  double volume_ = 0;
};

}  // namespace lsmbs
