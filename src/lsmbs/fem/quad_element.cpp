#include "lsmbs/fem/quad_element.hpp"

#include <algorithm>
#include <cmath>

#include "lsmbs/core/error.hpp"

namespace lsmbs {
namespace {

constexpr double kXi[4] = {-1, 1, 1, -1};
constexpr double kEta[4] = {-1, -1, 1, 1};

void shape(double xi, double eta, Eigen::Vector4d& N, Eigen::Matrix<double, 4, 2>& dN) {
  for (int i = 0; i < 4; ++i) {
    N[i] = 0.25 * (1 + kXi[i] * xi) * (1 + kEta[i] * eta);
    dN(i, 0) = 0.25 * kXi[i] * (1 + kEta[i] * eta);
    dN(i, 1) = 0.25 * kEta[i] * (1 + kXi[i] * xi);
  }
}

// Plane-stress constitutive matrix in Voigt form (E11, E22, 2E12).
Eigen::Matrix3d plane_stress(double E, double nu, bool normal, bool shear) {
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
Eigen::Matrix3d plane_stress_dnu(double E, double nu, bool normal, bool shear) {
  Eigen::Matrix3d D = Eigen::Matrix3d::Zero();
  const double c = E / (1 - nu * nu), dc = 2 * E * nu / ((1 - nu * nu) * (1 - nu * nu));
  if (normal) {
    D(0, 0) = D(1, 1) = dc;
    D(0, 1) = D(1, 0) = dc * nu + c;
  }
  if (shear) D(2, 2) = -E / (2 * (1 + nu) * (1 + nu));
  return D;
}

}  // namespace

QuadElement::QuadElement(const std::array<Vec2, 4>& X, QuadIntegration integration)
    : integration_(integration) {
  const double g = 1 / std::sqrt(3.0);
  const double gp[4][2] = {{-g, -g}, {g, -g}, {g, g}, {-g, g}};
  auto make = [&](double xi, double eta, double weight, Point& p, Eigen::Vector4d& N) {
    Eigen::Matrix<double, 4, 2> dN;
    shape(xi, eta, N, dN);
    Mat2 J = Mat2::Zero();  // J_ab = ∂X_a/∂ξ_b
    for (int i = 0; i < 4; ++i) J += X[i] * dN.row(i);
    const double det = J.determinant();
    if (!(det > 0)) throw Error("inverted or degenerate quadrilateral element (det J <= 0)");
    p.G = dN * J.inverse();
    p.w = weight * det;
  };
  for (int q = 0; q < 4; ++q) {
    Eigen::Vector4d N;
    make(gp[q][0], gp[q][1], 1.0, gauss_[q], N);
    unit_mass_ += gauss_[q].w * N * N.transpose();
    shape_int_ += gauss_[q].w * N;
    area_ += gauss_[q].w;
  }
  Eigen::Vector4d N;
  make(0, 0, 4.0, centre_, N);
  for (int c = 0; c < 4; ++c) {
    Eigen::Matrix<double, 4, 2> dN;
    shape(kXi[c], kEta[c], N, dN);
    Mat2 J = Mat2::Zero();
    for (int i = 0; i < 4; ++i) J += X[i] * dN.row(i);
    corner_det_J_[c] = J.determinant();
  }
}

namespace {

// Adds t·w·(Bᵀ D E, Bᵀ D B + geometric) at one integration point.
template <class Vec8, class Mat8>
void add_point(const Eigen::Matrix<double, 4, 2>& G, double tw, const Vec8& x,
               const Eigen::Matrix3d& D, Vec8& f, Mat8* K) {
  Mat2 F = Mat2::Zero();
  for (int i = 0; i < 4; ++i) F += Vec2(x[2 * i], x[2 * i + 1]) * G.row(i);
  const Mat2 C = F.transpose() * F;
  const Eigen::Vector3d E(0.5 * (C(0, 0) - 1), 0.5 * (C(1, 1) - 1), C(0, 1));
  const Eigen::Vector3d S = D * E;
  Eigen::Matrix<double, 3, 8> B;
  for (int j = 0; j < 4; ++j)
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
    const Eigen::Matrix4d Gs = G * Sm * G.transpose();
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        (*K)(2 * i, 2 * j) += tw * Gs(i, j);
        (*K)(2 * i + 1, 2 * j + 1) += tw * Gs(i, j);
      }
  }
}

template <class Vec8>
double point_energy(const Eigen::Matrix<double, 4, 2>& G, double tw, const Vec8& x,
                    const Eigen::Matrix3d& D) {
  Mat2 F = Mat2::Zero();
  for (int i = 0; i < 4; ++i) F += Vec2(x[2 * i], x[2 * i + 1]) * G.row(i);
  const Mat2 C = F.transpose() * F;
  const Eigen::Vector3d E(0.5 * (C(0, 0) - 1), 0.5 * (C(1, 1) - 1), C(0, 1));
  return 0.5 * tw * E.dot(D * E);
}

}  // namespace

void QuadElement::internal_force(const Vec8& x, double E, double nu, double t, Vec8& f,
                                 Mat8* K) const {
  f.setZero();
  if (K) K->setZero();
  const bool sri = integration_ == QuadIntegration::kSelectiveShear;
  const Eigen::Matrix3d D = plane_stress(E, nu, true, !sri);
  for (const auto& p : gauss_) add_point(p.G, t * p.w, x, D, f, K);
  if (sri) add_point(centre_.G, t * centre_.w, x, plane_stress(E, nu, false, true), f, K);
}

void QuadElement::internal_force_nu_derivative(const Vec8& x, double E, double nu, double t,
                                               Vec8& df) const {
  df.setZero();
  const bool sri = integration_ == QuadIntegration::kSelectiveShear;
  const Eigen::Matrix3d D = plane_stress_dnu(E, nu, true, !sri);
  for (const auto& p : gauss_) add_point<Vec8, Mat8>(p.G, t * p.w, x, D, df, nullptr);
  if (sri)
    add_point<Vec8, Mat8>(centre_.G, t * centre_.w, x, plane_stress_dnu(E, nu, false, true), df,
                          nullptr);
}

double QuadElement::strain_energy(const Vec8& x, double E, double nu, double t) const {
  const bool sri = integration_ == QuadIntegration::kSelectiveShear;
  const Eigen::Matrix3d D = plane_stress(E, nu, true, !sri);
  double W = 0;
  for (const auto& p : gauss_) W += point_energy(p.G, t * p.w, x, D);
  if (sri) W += point_energy(centre_.G, t * centre_.w, x, plane_stress(E, nu, false, true));
  return W;
}

double QuadElement::min_det_F(const Vec8& x) const {
  auto det_at = [&](const Point& p) {
    Mat2 F = Mat2::Zero();
    for (int i = 0; i < 4; ++i) F += Vec2(x[2 * i], x[2 * i + 1]) * p.G.row(i);
    return F.determinant();
  };
  double m = det_at(centre_);
  for (const auto& p : gauss_) m = std::min(m, det_at(p));
  return m;
}

double QuadElement::min_corner_det_F(const Vec8& x) const {
  double m = INFINITY;
  for (int c = 0; c < 4; ++c) {
    if (!(corner_det_J_[c] > 0)) continue;
    Eigen::Vector4d N;
    Eigen::Matrix<double, 4, 2> dN;
    shape(kXi[c], kEta[c], N, dN);
    Mat2 j = Mat2::Zero();  // ∂x/∂ξ
    for (int i = 0; i < 4; ++i) j += Vec2(x[2 * i], x[2 * i + 1]) * dN.row(i);
    m = std::min(m, j.determinant() / corner_det_J_[c]);
  }
  return m;
}

void QuadElement::centre_strain(const Vec8& x, Eigen::Vector3d& Ev, Mat2& F) const {
  F.setZero();
  for (int i = 0; i < 4; ++i) F += Vec2(x[2 * i], x[2 * i + 1]) * centre_.G.row(i);
  const Mat2 C = F.transpose() * F;
  Ev = Eigen::Vector3d(0.5 * (C(0, 0) - 1), 0.5 * (C(1, 1) - 1), C(0, 1));
}

}  // namespace lsmbs
