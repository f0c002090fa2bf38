#pragma once
// The plane-stress St Venant–Kirchhoff kernels that the planar elements share (an internal header
// of fem/): the constitutive matrix D in Voigt form (E11, E22, 2E12) and its derivative in ν, and
// one integration point's contribution to the internal force, tangent and strain energy of an
// element of N nodes in absolute nodal coordinates:
//   F = Σ x_I ⊗ ∇_X N_I,  E = ½(FᵀF − I),  S = D E,  f += t w Bᵀ S,
//   K += t w (Bᵀ D B + geometric: (∇N S ∇Nᵀ) ⊗ I₂).
#include <Eigen/Dense>

#include "lsmbs/core/types.hpp"

namespace lsmbs::plane {

// Plane-stress constitutive matrix in Voigt form (E11, E22, 2E12).
inline Eigen::Matrix3d plane_stress(double E, double nu, bool normal, bool shear) {
  Eigen::Matrix3d D = Eigen::Matrix3d::Zero();
  const double c = E / (1 - nu * nu);
  if (normal) {
    D(0, 0) = D(1, 1) = c;
    D(0, 1) = D(1, 0) = c * nu;
  }
  if (shear) D(2, 2) = c * (1 - nu) / 2;
  return D;
}

// ∂D/∂ν of plane_stress: c' = dc/dν = 2Eν/(1 − ν²)², ∂(cν)/∂ν = c'ν + c, and the shear modulus
// c(1 − ν)/2 = E/(2(1 + ν)) has derivative −E/(2(1 + ν)²).
inline Eigen::Matrix3d plane_stress_dnu(double E, double nu, bool normal, bool shear) {
  Eigen::Matrix3d D = Eigen::Matrix3d::Zero();
  const double c = E / (1 - nu * nu), dc = 2 * E * nu / ((1 - nu * nu) * (1 - nu * nu));
  if (normal) {
    D(0, 0) = D(1, 1) = dc;
    D(0, 1) = D(1, 0) = dc * nu + c;
  }
  if (shear) D(2, 2) = -E / (2 * (1 + nu) * (1 + nu));
  return D;
}

// Adds t·w·(Bᵀ D E, Bᵀ D B + geometric) at one integration point.
template <int N, class VecX, class MatX>
void add_point(const Eigen::Matrix<double, N, 2>& G, double tw, const VecX& x,
               const Eigen::Matrix3d& D, VecX& f, MatX* K) {
  Mat2 F = Mat2::Zero();
  for (int i = 0; i < N; ++i) F += Vec2(x[2 * i], x[2 * i + 1]) * G.row(i);
  const Mat2 C = F.transpose() * F;
  const Eigen::Vector3d E(0.5 * (C(0, 0) - 1), 0.5 * (C(1, 1) - 1), C(0, 1));
  const Eigen::Vector3d S = D * E;
  Eigen::Matrix<double, 3, 2 * N> B;
  for (int j = 0; j < N; ++j)
    for (int a = 0; a < 2; ++a) {
      B(0, 2 * j + a) = F(a, 0) * G(j, 0);
      B(1, 2 * j + a) = F(a, 1) * G(j, 1);
      B(2, 2 * j + a) = F(a, 0) * G(j, 1) + F(a, 1) * G(j, 0);
    }
  f.noalias() += tw * B.transpose() * S;
  if (K) {
    K->noalias() += tw * B.transpose() * D * B;
    Mat2 Sm;
    Sm << S[0], S[2], S[2], S[1];
    const Eigen::Matrix<double, N, N> Gs = G * Sm * G.transpose();
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) {
        (*K)(2 * i, 2 * j) += tw * Gs(i, j);
        (*K)(2 * i + 1, 2 * j + 1) += tw * Gs(i, j);
      }
  }
}

template <int N, class VecX>
double point_energy(const Eigen::Matrix<double, N, 2>& G, double tw, const VecX& x,
                    const Eigen::Matrix3d& D) {
  Mat2 F = Mat2::Zero();
  for (int i = 0; i < N; ++i) F += Vec2(x[2 * i], x[2 * i + 1]) * G.row(i);
  const Mat2 C = F.transpose() * F;
  const Eigen::Vector3d E(0.5 * (C(0, 0) - 1), 0.5 * (C(1, 1) - 1), C(0, 1));
  return 0.5 * tw * E.dot(D * E);
}

}  // namespace lsmbs::plane
