// Micro benchmarks (Google Benchmark) of the pieces of one generalized-α step on the §6 robot
// arm (2671 DOFs): element force and tangent, residual and iteration-matrix assembly into the
// fixed pattern, KLU refactorization and solve, the volume-fraction mapping, and a whole step.
// The "floor" of a step is refactor + solve + residual + tangent assembly; docs/performance.md
// records the ratio (average step time) / floor.
//
//   cmake -S . -B build -DLSMBS_BUILD_BENCH=ON && cmake --build build -j2
//   build/bench/lsmbs_bench --benchmark_out=bench.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/linalg/sparse_lu.hpp"

using namespace lsmbs;

namespace {

struct Fixture {
  Case cs = load_case(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm_holes.json");
  State s;
  AlphaCoefficients c = AlphaCoefficients::make(0.8, 0.005);
  double k = 0;
  std::vector<double> vals;
  Vec R;
  Fixture() {
    s = cs.initial;
    s.v.setZero(cs.model->nq());
    s.a.setZero(cs.model->nq());
    s.lambda.setZero(cs.model->nc());
    k = GeneralizedAlpha::automatic_scaling(*cs.model, cs.model->params(), s, c);
  }
  static Fixture& get() {
    static Fixture f;
    return f;
  }
};

void BM_QuadForceAndTangent(benchmark::State& st) {
  auto& f = Fixture::get();
  const auto& b = *f.cs.model->flexible_bodies()[0];
  double x[8], r[8], K[64];
  b.element_coordinates(0, f.s.q, x);
  for (auto _ : st) {
    b.elements[0]->internal_force(x, 72e9, 0.3, 0.0025, r, K);
    benchmark::DoNotOptimize(K);
  }
}
BENCHMARK(BM_QuadForceAndTangent);

void BM_ResidualAssembly(benchmark::State& st) {
  auto& f = Fixture::get();
  for (auto _ : st) {
    f.cs.model->residual(f.s, f.cs.model->params(), f.k, f.k, f.R);
    benchmark::DoNotOptimize(f.R.data());
  }
}
BENCHMARK(BM_ResidualAssembly)->Unit(benchmark::kMicrosecond);

void BM_IterationMatrixAssembly(benchmark::State& st) {
  auto& f = Fixture::get();
  for (auto _ : st) {
    f.cs.model->iteration_matrix(f.s, f.cs.model->params(), {f.c.beta_p, f.c.gamma_p, 1}, f.k, f.k,
                                 f.vals);
    benchmark::DoNotOptimize(f.vals.data());
  }
}
BENCHMARK(BM_IterationMatrixAssembly)->Unit(benchmark::kMicrosecond);

void BM_KluRefactorAndSolve(benchmark::State& st) {
  auto& f = Fixture::get();
  f.cs.model->iteration_matrix(f.s, f.cs.model->params(), {f.c.beta_p, f.c.gamma_p, 1}, f.k, f.k,
                               f.vals);
  SparseLU lu;
  lu.analyze(f.cs.model->pattern());
  lu.factor(f.vals);
  Vec b = Vec::Ones(f.cs.model->n());
  for (auto _ : st) {
    lu.factor(f.vals);
    Vec x = b;
    lu.solve(x);
    benchmark::DoNotOptimize(x.data());
  }
}
BENCHMARK(BM_KluRefactorAndSolve)->Unit(benchmark::kMicrosecond);

void BM_VolumeFractionMapping(benchmark::State& st) {
  auto& f = Fixture::get();
  const auto& bd = f.cs.design->bodies[0];
  const Vec p = f.cs.design->initial();
  Vec mu;
  SpMat J;
  for (auto _ : st) {
    bd.map->map(p, mu, st.range(0) ? &J : nullptr);
    benchmark::DoNotOptimize(mu.data());
  }
}
BENCHMARK(BM_VolumeFractionMapping)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_GeneralizedAlphaStep(benchmark::State& st) {
  auto& f = Fixture::get();
  GeneralizedAlphaOptions o = f.cs.simulation;
  o.t_end = 0.5;  // 100 steps
  for (auto _ : st) {
    const auto sum = GeneralizedAlpha(o).run(*f.cs.model, f.cs.model->params(), f.cs.initial, {});
    st.counters["steps"] = static_cast<double>(sum.steps);
    st.counters["newton_per_step"] = static_cast<double>(sum.newton_iterations) / sum.steps;
  }
  st.SetItemsProcessed(st.iterations() * 100);
}
BENCHMARK(BM_GeneralizedAlphaStep)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
