#include "lsmbs/fem/quad_element.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/plane_kernels.hpp"

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
  unit_mass_dyn_ = unit_mass_;
  shape_int_dyn_ = shape_int_;
  centre_G_ = centre_.G;
  for (int c = 0; c < 4; ++c) {
    Eigen::Matrix<double, 4, 2> dN;
    shape(kXi[c], kEta[c], N, dN);
    Mat2 J = Mat2::Zero();
    for (int i = 0; i < 4; ++i) J += X[i] * dN.row(i);
    corner_det_J_[c] = J.determinant();
  }
}

void QuadElement::internal_force(const Vec8& x, double E, double nu, double t, Vec8& f,
                                 Mat8* K) const {
  f.setZero();
  if (K) K->setZero();
  const bool sri = integration_ == QuadIntegration::kSelectiveShear;
  const Eigen::Matrix3d D = plane::plane_stress(E, nu, true, !sri);
  for (const auto& p : gauss_) plane::add_point<4>(p.G, t * p.w, x, D, f, K);
  if (sri)
    plane::add_point<4>(centre_.G, t * centre_.w, x, plane::plane_stress(E, nu, false, true), f, K);
}

void QuadElement::internal_force_nu_derivative(const Vec8& x, double E, double nu, double t,
                                               Vec8& df) const {
  df.setZero();
  const bool sri = integration_ == QuadIntegration::kSelectiveShear;
  const Eigen::Matrix3d D = plane::plane_stress_dnu(E, nu, true, !sri);
  for (const auto& p : gauss_) plane::add_point<4, Vec8, Mat8>(p.G, t * p.w, x, D, df, nullptr);
  if (sri)
    plane::add_point<4, Vec8, Mat8>(centre_.G, t * centre_.w, x,
                                    plane::plane_stress_dnu(E, nu, false, true), df, nullptr);
}

double QuadElement::strain_energy(const Vec8& x, double E, double nu, double t) const {
  const bool sri = integration_ == QuadIntegration::kSelectiveShear;
  const Eigen::Matrix3d D = plane::plane_stress(E, nu, true, !sri);
  double W = 0;
  for (const auto& p : gauss_) W += plane::point_energy<4>(p.G, t * p.w, x, D);
  if (sri)
    W += plane::point_energy<4>(centre_.G, t * centre_.w, x,
                                plane::plane_stress(E, nu, false, true));
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

// ---- PlaneElement on interleaved coordinates: the fixed-size functions above, unchanged
void QuadElement::internal_force(const double* x, double E, double nu, double t, double* f,
                                 double* K) const {
  Vec8 fv;
  if (!K) {
    internal_force(Eigen::Map<const Vec8>(x), E, nu, t, fv, nullptr);
  } else {
    Mat8 Kv;
    internal_force(Eigen::Map<const Vec8>(x), E, nu, t, fv, &Kv);
    Eigen::Map<Mat8>{K} = Kv;
  }
  Eigen::Map<Vec8>{f} = fv;
}

void QuadElement::internal_force_nu_derivative(const double* x, double E, double nu, double t,
                                               double* df) const {
  Vec8 d;
  internal_force_nu_derivative(Eigen::Map<const Vec8>(x), E, nu, t, d);
  Eigen::Map<Vec8>{df} = d;
}

double QuadElement::strain_energy(const double* x, double E, double nu, double t) const {
  return strain_energy(Vec8(Eigen::Map<const Vec8>(x)), E, nu, t);
}

void QuadElement::centre_strain(const double* x, Eigen::Vector3d& Ev, Mat2& F) const {
  centre_strain(Vec8(Eigen::Map<const Vec8>(x)), Ev, F);
}

double QuadElement::min_det_F(const double* x) const {
  return min_det_F(Vec8(Eigen::Map<const Vec8>(x)));
}

double QuadElement::min_corner_det_F(const double* x) const {
  return min_corner_det_F(Vec8(Eigen::Map<const Vec8>(x)));
}

// ---- the quadrilateral's shape
double QuadShape::area(const Vec2* X) const {
  const Vec2 d1 = X[2] - X[0], d2 = X[3] - X[1];
  return 0.5 * (d1.x() * d2.y() - d1.y() * d2.x());
}

double QuadShape::min_det_J(const Vec2* X) const {
  // det J at the 2 × 2 Gauss points, where the element integrates
  const double g = 1 / std::sqrt(3.0);
  double lo = std::numeric_limits<double>::infinity();
  for (const double xi : {-g, g})
    for (const double eta : {-g, g}) {
      const Vec2 dxi = 0.25 * ((1 - eta) * (X[1] - X[0]) + (1 + eta) * (X[2] - X[3]));
      const Vec2 deta = 0.25 * ((1 - xi) * (X[3] - X[0]) + (1 + xi) * (X[2] - X[1]));
      lo = std::min(lo, dxi.x() * deta.y() - dxi.y() * deta.x());
    }
  return lo;
}

void QuadShape::samples(const Vec2* X, int n, std::vector<CellSample>& out) const {
  // the midpoints of n × n sub-cells of the parent square, weighted by det J of the bilinear map
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double xi = -1 + (2 * i + 1.0) / n, eta = -1 + (2 * j + 1.0) / n;
      const double N0 = 0.25 * (1 - xi) * (1 - eta), N1 = 0.25 * (1 + xi) * (1 - eta),
                   N2 = 0.25 * (1 + xi) * (1 + eta), N3 = 0.25 * (1 - xi) * (1 + eta);
      const Vec2 x = N0 * X[0] + N1 * X[1] + N2 * X[2] + N3 * X[3];
      const Vec2 dxi = 0.25 * ((1 - eta) * (X[1] - X[0]) + (1 + eta) * (X[2] - X[3]));
      const Vec2 deta = 0.25 * ((1 - xi) * (X[3] - X[0]) + (1 + xi) * (X[2] - X[1]));
      out.push_back({x, (dxi.x() * deta.y() - dxi.y() * deta.x()) * (4.0 / (n * n))});
    }
}

void QuadShape::contour(const Vec2* X, const double* f,
                        std::vector<std::pair<Vec2, Vec2>>& out) const {
  // marching squares: edge k joins nodes k and k + 1, crossed where f changes sign (linear
  // along the edge)
  Vec2 cross[4];
  bool cut[4];
  int ncut = 0;
  for (int k = 0; k < 4; ++k) {
    const int l = (k + 1) % 4;
    cut[k] = (f[k] > 0) != (f[l] > 0);
    if (cut[k]) {
      cross[k] = X[k] + f[k] / (f[k] - f[l]) * (X[l] - X[k]);
      ++ncut;
    }
  }
  if (ncut == 2) {
    int a = -1, b = -1;
    for (int k = 0; k < 4; ++k)
      if (cut[k]) (a < 0 ? a : b) = k;
    out.emplace_back(cross[a], cross[b]);
  } else if (ncut == 4) {  // saddle: the centre's sign says which corners are cut off
    const bool centre = (f[0] + f[1] + f[2] + f[3]) / 4 > 0;
    if (centre == (f[0] > 0)) {
      out.emplace_back(cross[0], cross[1]), out.emplace_back(cross[2], cross[3]);
    } else {
      out.emplace_back(cross[3], cross[0]), out.emplace_back(cross[1], cross[2]);
    }
  }
}

}  // namespace lsmbs
