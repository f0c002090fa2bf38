// Uses the installed library: loads a case, simulates it, and checks the piston's stroke
// against the closed form 2r (r = 45 mm) of the shipped rigid slider-crank.
#include <cmath>
#include <cstdio>

#include "lsmbs/core/version.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/runs/simulate.hpp"

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  lsmbs::Case cs = lsmbs::load_case(argv[1]);
  const auto r = lsmbs::run_simulation(cs);
  const double stroke = r.responses.at("max_piston_x") - r.responses.at("min_piston_x");
  std::printf("lsmbs %s: stroke %.6f m (2 r = 0.09 m)\n", lsmbs::kVersion, stroke);
  return r.integrator.ok && std::abs(stroke - 0.09) < 1e-4 ? 0 : 1;
}
