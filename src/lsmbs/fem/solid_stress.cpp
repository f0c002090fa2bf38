#include "lsmbs/fem/solid_stress.hpp"

#include <cmath>

namespace lsmbs {

double solid_centre_von_mises(const SolidElement& el, const double* x, double E, double nu,
                              double* dvm) {
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), G = E / (2 * (1 + nu));
  const Mat3 I = Mat3::Identity();
  const Mat3 F = el.centre_F(x);
  const Mat3 Egl = 0.5 * (F.transpose() * F - I);
  const Mat3 S = lambda * Egl.trace() * I + 2 * G * Egl;
  const double J = F.determinant();
  const Mat3 sigma = F * S * F.transpose() / J;
  const Mat3 dev = sigma - sigma.trace() / 3 * I;
  const double vm = std::sqrt(1.5 * dev.squaredNorm());
  if (!dvm) return vm;
  const int n = el.num_nodes();
  for (int k = 0; k < 3 * n; ++k) dvm[k] = 0;
  if (!(vm > 0)) return vm;
  // ∂σ_vm/∂F_ab along each unit dF = e_a e_bᵀ:
  //   dE = sym(Fᵀ dF), dS = λ tr(dE) I + 2G dE, dJ = J tr(F⁻¹ dF),
  //   dσ = (dF S Fᵀ + F dS Fᵀ + F S dFᵀ)/J − σ dJ/J,  dσ_vm = 3/2 dev σ : dσ / σ_vm
  const Mat3 Finv = F.inverse();
  Mat3 dvm_dF;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      Mat3 dF = Mat3::Zero();
      dF(a, b) = 1;
      const Mat3 dE = 0.5 * (dF.transpose() * F + F.transpose() * dF);
      const Mat3 dS = lambda * dE.trace() * I + 2 * G * dE;
      const double dJ_J = Finv(b, a);  // tr(F⁻¹ e_a e_bᵀ)
      const Mat3 dsigma =
          (dF * S * F.transpose() + F * dS * F.transpose() + F * S * dF.transpose()) / J -
          sigma * dJ_J;
      dvm_dF(a, b) = 1.5 * (dev.cwiseProduct(dsigma)).sum() / vm;
    }
  // F is linear in x: the gradients ∇N_I (rows of Gm) from F at unit coordinates x = e_(I, 0)
  double unit[kMaxLocalDofs] = {};
  for (int node = 0; node < n; ++node) {
    unit[3 * node] = 1;
    const Mat3 Fi = el.centre_F(unit);  // row 0 = ∇N_Iᵀ
    unit[3 * node] = 0;
    for (int k = 0; k < 3; ++k) dvm[3 * node + k] = dvm_dF.row(k).dot(Fi.row(0));
  }
  return vm;
}

}  // namespace lsmbs
