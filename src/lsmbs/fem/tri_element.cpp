#include "lsmbs/fem/tri_element.hpp"

#include <cmath>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/plane_kernels.hpp"

namespace lsmbs {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

TriElement::TriElement(const std::array<Vec2, 3>& X) {
  Mat2 J;  // J_ab = ∂X_a/∂ξ_b with N0 = 1 − ξ − η, N1 = ξ, N2 = η
  J.col(0) = X[1] - X[0];
  J.col(1) = X[2] - X[0];
  const double det = J.determinant();
  if (!(det > 0)) throw Error("inverted or degenerate triangular element (det J <= 0)");
  Eigen::Matrix<double, 3, 2> dN;
  dN << -1, -1, 1, 0, 0, 1;
  G_ = dN * J.inverse();
  G_dyn_ = G_;
  area_ = 0.5 * det;
  unit_mass_ = Eigen::MatrixXd::Constant(3, 3, area_ / 12);
  unit_mass_.diagonal().setConstant(area_ / 6);
  shape_int_ = Eigen::VectorXd::Constant(3, area_ / 3);
}

void TriElement::internal_force(const double* x, double E, double nu, double t, double* f,
                                double* K) const {
  const Vec6 xv = Eigen::Map<const Vec6>(x);
  Vec6 fv = Vec6::Zero();
  Mat6 Kv = Mat6::Zero();
  plane::add_point<3>(G_, t * area_, xv, plane::plane_stress(E, nu, true, true), fv,
                      K ? &Kv : nullptr);
  Eigen::Map<Vec6>{f} = fv;
  if (K) Eigen::Map<Mat6>{K} = Kv;
}

void TriElement::internal_force_nu_derivative(const double* x, double E, double nu, double t,
                                              double* df) const {
  const Vec6 xv = Eigen::Map<const Vec6>(x);
  Vec6 d = Vec6::Zero();
  plane::add_point<3, Vec6, Mat6>(G_, t * area_, xv, plane::plane_stress_dnu(E, nu, true, true), d,
                                  nullptr);
  Eigen::Map<Vec6>{df} = d;
}

double TriElement::strain_energy(const double* x, double E, double nu, double t) const {
  return plane::point_energy<3>(G_, t * area_, Vec6(Eigen::Map<const Vec6>(x)),
                                plane::plane_stress(E, nu, true, true));
}

void TriElement::centre_strain(const double* x, Eigen::Vector3d& Ev, Mat2& F) const {
  F.setZero();
  for (int i = 0; i < 3; ++i) F += Vec2(x[2 * i], x[2 * i + 1]) * G_.row(i);
  const Mat2 C = F.transpose() * F;
  Ev = Eigen::Vector3d(0.5 * (C(0, 0) - 1), 0.5 * (C(1, 1) - 1), C(0, 1));
}

double TriElement::min_det_F(const double* x) const {
  Mat2 F = Mat2::Zero();
  for (int i = 0; i < 3; ++i) F += Vec2(x[2 * i], x[2 * i + 1]) * G_.row(i);
  return F.determinant();
}

double TriShape::area(const Vec2* X) const {
  const Vec2 a = X[1] - X[0], b = X[2] - X[0];
  return 0.5 * (a.x() * b.y() - a.y() * b.x());
}

void TriShape::samples(const Vec2* X, int n, std::vector<CellSample>& out) const {
  // the n² sub-triangles of the uniform subdivision, "upward" ones (i, j), (i+1, j), (i, j+1)
  // and "downward" ones (i+1, j), (i+1, j+1), (i, j+1) in units of 1/n of (ξ, η); each has the
  // area A/n² and is sampled at its centroid
  const double w = area(X) / (static_cast<double>(n) * n);
  auto at = [&](double xi, double eta) {
    return Vec2(X[0] + xi * (X[1] - X[0]) + eta * (X[2] - X[0]));
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i + j < n; ++i) {
      out.push_back({at((3 * i + 1.0) / (3 * n), (3 * j + 1.0) / (3 * n)), w});
      if (i + j + 2 <= n) out.push_back({at((3 * i + 2.0) / (3 * n), (3 * j + 2.0) / (3 * n)), w});
    }
}

void TriShape::contour(const Vec2* X, const double* f,
                       std::vector<std::pair<Vec2, Vec2>>& out) const {
  Vec2 cross[3];
  int ncut = 0;
  for (int k = 0; k < 3; ++k) {
    const int l = (k + 1) % 3;
    if ((f[k] > 0) != (f[l] > 0)) cross[ncut++] = X[k] + f[k] / (f[k] - f[l]) * (X[l] - X[k]);
  }
  if (ncut == 2) out.emplace_back(cross[0], cross[1]);
}

}  // namespace lsmbs
