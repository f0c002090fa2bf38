#include "lsmbs/responses/mesh_convergence.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace lsmbs {

namespace {
std::string g(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}
}  // namespace

MeshConvergence mesh_convergence(double r3, double r2, double r1, double h3, double h2, double h1,
                                 double tolerance) {
  MeshConvergence m;
  const double e21 = r1 - r2, e32 = r2 - r3;
  const double scale = std::max({std::abs(r1), std::abs(r2), std::abs(r3)});
  const std::string values = "values " + g(r3) + ", " + g(r2) + ", " + g(r1) + " (coarse to fine)";
  if (!std::isfinite(r1) || !std::isfinite(r2) || !std::isfinite(r3)) {
    m.gci = std::numeric_limits<double>::infinity();
    m.explanation = values + ": a value is not finite";
    return m;
  }
  // changes at round-off of the values: a response the mesh does not change (a rigid body's)
  const double noise = 64 * std::numeric_limits<double>::epsilon() * scale;
  if (std::abs(e21) <= noise && std::abs(e32) <= noise) {
    m.verdict = MeshConvergence::Verdict::kIndependent;
    m.extrapolated = r1;
    m.explanation = values + ": independent of the mesh (changes at round-off)";
    return m;
  }
  if (!(std::abs(e21) < std::abs(e32))) {
    m.gci = std::numeric_limits<double>::infinity();
    m.explanation = values + ": the change does not shrink with the mesh (" + g(e32) + " then " +
                    g(e21) + "); not converged";
    return m;
  }
  const double r21 = h2 / h1, r32 = h3 / h2;
  const double s = (e32 / e21) >= 0 ? 1.0 : -1.0;
  double p = std::abs(std::log(std::abs(e32 / e21))) / std::log(r21);
  for (int it = 0; it < 100; ++it) {  // Celik's fixed point (exact for r21 = r32: q = 0)
    const double q = std::log((std::pow(r21, p) - s) / (std::pow(r32, p) - s));
    const double pn = std::abs(std::log(std::abs(e32 / e21)) + q) / std::log(r21);
    if (!std::isfinite(pn)) break;
    const bool done = std::abs(pn - p) <= 1e-12 * std::max(1.0, p);
    p = pn;
    if (done) break;
  }
  m.order = p;
  const double denom = std::pow(r21, p) - 1;
  m.extrapolated = r1 + e21 / denom;
  m.gci = 1.25 * std::abs(e21 / (std::abs(r1) > 0 ? r1 : scale)) / denom;
  const bool ok = m.gci <= tolerance;
  m.verdict = ok ? MeshConvergence::Verdict::kConverged : MeshConvergence::Verdict::kNotConverged;
  m.explanation = values + ": observed order " + g(p) + ", grid convergence index " + g(m.gci) +
                  (ok ? " <= " : " > ") + g(tolerance) +
                  (ok ? ""
                      : "; not converged in the mesh: refine it, or use a response that " +
                            std::string("converges (a stress at a sharp corner does not)"));
  return m;
}

}  // namespace lsmbs
