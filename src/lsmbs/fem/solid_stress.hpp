#pragma once
// The von Mises stress at a solid element's centre, for the stress measure of solid bodies and
// the pictures: the Cauchy stress σ = F S Fᵀ / det F with S = λ tr(E) I + 2G E (St Venant–
// Kirchhoff, the solid material's E and ν) at the centre's deformation gradient F, where the
// hexahedron's enhanced modes vanish (hex_element.hpp), and σ_vm = √(3/2 dev σ : dev σ).
#include "lsmbs/fem/solid_element.hpp"

namespace lsmbs {

/// σ_vm at the element's centre for node coordinates x (3 per node, interleaved). With dvm
/// non-null it receives ∂σ_vm/∂x (3 × nodes entries), exact: F is linear in x (F = Σ_I x_I ∇N_Iᵀ),
/// and σ_vm(F) is differentiated in closed form along each of F's nine components. At σ_vm = 0
/// (an unstrained element) the subgradient 0 is returned.
double solid_centre_von_mises(const SolidElement& el, const double* x, double E, double nu,
                              double* dvm = nullptr);

}  // namespace lsmbs
