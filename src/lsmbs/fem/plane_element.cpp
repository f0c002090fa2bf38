#include "lsmbs/fem/plane_element.hpp"

#include <algorithm>
#include <cmath>

namespace lsmbs {
namespace {

Mat2 pk2(const Mat2& F, double c, double nu) {  // S = D E, c = E0/(1 − ν²)
  const Mat2 E = 0.5 * (F.transpose() * F - Mat2::Identity());
  Mat2 S;
  S << c * (E(0, 0) + nu * E(1, 1)), c * (1 - nu) * E(0, 1), c * (1 - nu) * E(0, 1),
      c * (E(1, 1) + nu * E(0, 0));
  return S;
}

}  // namespace

PointStress plane_centre_stress(Eigen::Ref<const Eigen::MatrixX2d> G, const double* x, double E0,
                                double nu, bool derivatives) {
  const auto n = static_cast<int>(G.rows());
  Mat2 F = Mat2::Zero();
  for (int I = 0; I < n; ++I) F += Vec2(x[2 * I], x[2 * I + 1]) * G.row(I);
  const double c = E0 / (1 - nu * nu), J = F.determinant();
  const Mat2 S = pk2(F, c, nu);
  const Mat2 sig = F * S * F.transpose() / J;
  PointStress r;
  r.dvm.setZero(2 * n);
  const double s11 = sig(0, 0), s22 = sig(1, 1), s12 = sig(0, 1);
  r.vm = std::sqrt(std::max(0.0, s11 * s11 - s11 * s22 + s22 * s22 + 3 * s12 * s12));
  if (!derivatives || r.vm == 0) return r;  // subgradient 0 at zero stress
  const Mat2 Finv = F.inverse();
  for (int k = 0; k < 2 * n; ++k) {
    Mat2 dF = Mat2::Zero();
    dF.row(k % 2) = G.row(k / 2);
    const Mat2 dE = 0.5 * (dF.transpose() * F + F.transpose() * dF);
    Mat2 dS;
    dS << c * (dE(0, 0) + nu * dE(1, 1)), c * (1 - nu) * dE(0, 1), c * (1 - nu) * dE(0, 1),
        c * (dE(1, 1) + nu * dE(0, 0));
    const Mat2 dtau = dF * S * F.transpose() + F * dS * F.transpose() + F * S * dF.transpose();
    const double dJ = J * (Finv * dF).trace();
    const Mat2 dsig = (dtau - sig * dJ) / J;
    r.dvm[k] =
        ((2 * s11 - s22) * dsig(0, 0) + (2 * s22 - s11) * dsig(1, 1) + 6 * s12 * dsig(0, 1)) /
        (2 * r.vm);
  }
  return r;
}

PointStress PlaneElement::centre_stress(const double* x, double E0, double nu,
                                        bool derivatives) const {
  return plane_centre_stress(centre_gradients(), x, E0, nu, derivatives);
}

}  // namespace lsmbs
