#pragma once
// Whether a response has converged in the mesh, from its values on three meshes refined by a
// constant-ish ratio (the mesh study of `lsmbs verify`): Richardson extrapolation with the
// observed order and Roache's grid convergence index (GCI) of the finest mesh, computed as in
// Celik et al., "Procedure for estimation and reporting of uncertainty due to discretization in
// CFD applications", J. Fluids Eng. 130 (2008) 078001:
//   ε21 = R1 − R2, ε32 = R2 − R3 (1 finest), s = sign(ε32/ε21),
//   p = |ln|ε32/ε21| + ln((r21^p − s)/(r32^p − s))| / ln r21 (fixed point),
//   GCI = 1.25 |ε21/R1| / (r21^p − 1).
// A response whose change does not shrink from the coarse pair to the fine pair (|ε21| ≥ |ε32|)
// has not converged, whatever its size: a peak stress at a re-entrant corner grows without bound
// (13.1, 16.8, 19.2 MPa at 128, 512, 2048 elements).
#include <string>

namespace lsmbs {

struct MeshConvergence {
  enum class Verdict { kConverged, kNotConverged, kIndependent };
  Verdict verdict = Verdict::kNotConverged;
  double order = 0;         ///< observed order p (0 when not converging)
  double gci = 0;           ///< relative error estimate of the finest value (inf: not converging)
  double extrapolated = 0;  ///< Richardson extrapolation R1 + ε21 / (r21^p − 1)
  std::string explanation;  ///< one sentence: the values, the changes and the verdict's reason
  bool pass() const { return verdict != Verdict::kNotConverged; }
};

/// Values r3 (coarsest), r2, r1 (finest) on meshes of characteristic sizes h3 > h2 > h1 (e.g.
/// 1/sqrt(elements)); `tolerance` bounds the GCI of the finest mesh.
MeshConvergence mesh_convergence(double r3, double r2, double r1, double h3, double h2, double h1,
                                 double tolerance);

}  // namespace lsmbs
