#include "lsmbs/sensitivity/wire.hpp"

#include <cstring>
#include <stdexcept>

namespace lsmbs {
namespace {

class Writer {
 public:
  template <class T>
  void raw(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void str(const std::string& s) {
    raw(static_cast<uint64_t>(s.size()));
    out += s;
  }
  void doubles(const double* d, size_t n) {
    raw(static_cast<uint64_t>(n));
    out.append(reinterpret_cast<const char*>(d), n * sizeof(double));
  }
  void vec(const std::vector<double>& v) { doubles(v.data(), v.size()); }
  void mat(const Mat& m) {
    raw(static_cast<int64_t>(m.rows()));
    raw(static_cast<int64_t>(m.cols()));
    out.append(reinterpret_cast<const char*>(m.data()), sizeof(double) * m.size());
  }
  std::string out;
};

class Reader {
 public:
  explicit Reader(const std::string& b) : b_(b) {}
  template <class T>
  T raw() {
    T v;
    need(sizeof(T));
    std::memcpy(&v, b_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  std::string str() {
    const auto n = raw<uint64_t>();
    need(n);
    std::string s = b_.substr(at_, n);
    at_ += n;
    return s;
  }
  std::vector<double> vec() {
    const auto n = raw<uint64_t>();
    need(n * sizeof(double));
    std::vector<double> v(n);
    std::memcpy(v.data(), b_.data() + at_, n * sizeof(double));
    at_ += n * sizeof(double);
    return v;
  }
  Mat mat() {
    const auto r = raw<int64_t>(), c = raw<int64_t>();
    Mat m(r, c);
    need(sizeof(double) * static_cast<size_t>(r * c));
    std::memcpy(m.data(), b_.data() + at_, sizeof(double) * static_cast<size_t>(r * c));
    at_ += sizeof(double) * static_cast<size_t>(r * c);
    return m;
  }

 private:
  void need(size_t n) const {
    if (at_ + n > b_.size()) throw std::runtime_error("wire: truncated record");
  }
  const std::string& b_;
  size_t at_ = 0;
};

void put(Writer& w, const ResponseSensitivity& r) {
  w.str(r.name);
  w.vec(r.values);
  w.vec(r.times);
  w.mat(r.gradient);
  w.raw(r.extreme_time);
}
ResponseSensitivity get_response(Reader& rd) {
  ResponseSensitivity r;
  r.name = rd.str();
  r.values = rd.vec();
  r.times = rd.vec();
  r.gradient = rd.mat();
  r.extreme_time = rd.raw<double>();
  return r;
}

void put(Writer& w, const IntegratorSummary& s) {
  w.raw(s.ok), w.raw(s.aborted), w.str(s.message), w.raw(s.t_reached);
  for (long v : {s.steps, s.newton_iterations, s.factorizations, s.residual_evaluations,
                 s.matrix_evaluations, s.halvings, s.fresh_factor_retries, s.increment_rejections,
                 s.inverted_element_rejections, s.folded_element_rejections, s.folded_element_steps,
                 s.linear_iterations, s.max_linear_iterations})
    w.raw(v);
  w.str(s.folded_first);
  w.raw(s.seconds);
  w.vec(s.halving_times);
  w.raw(s.k), w.raw(s.zeta), w.raw(s.force_floor), w.raw(s.wall_seconds);
  w.str(s.linear_solver);
  w.str(s.linear_preconditioner);
}
IntegratorSummary get_summary(Reader& rd) {
  IntegratorSummary s;
  s.ok = rd.raw<bool>(), s.aborted = rd.raw<bool>(), s.message = rd.str();
  s.t_reached = rd.raw<double>();
  for (long* v :
       {&s.steps, &s.newton_iterations, &s.factorizations, &s.residual_evaluations,
        &s.matrix_evaluations, &s.halvings, &s.fresh_factor_retries, &s.increment_rejections,
        &s.inverted_element_rejections, &s.folded_element_rejections, &s.folded_element_steps,
        &s.linear_iterations, &s.max_linear_iterations})
    *v = rd.raw<long>();
  s.folded_first = rd.str();
  s.seconds = rd.raw<IntegratorSummary::Seconds>();
  s.halving_times = rd.vec();
  s.k = rd.raw<double>(), s.zeta = rd.raw<double>(), s.force_floor = rd.raw<double>();
  s.wall_seconds = rd.raw<double>();
  s.linear_solver = rd.str();
  s.linear_preconditioner = rd.str();
  return s;
}

void put(Writer& w, const IdasStats& s) {
  w.raw(s.ok), w.str(s.message);
  for (long v :
       {s.steps, s.residual_evaluations, s.jacobian_evaluations, s.nonlinear_iterations,
        s.error_test_failures, s.nonlinear_convergence_failures, s.sensitivity_residual_evaluations,
        s.massless_velocities, s.adjoint_problems, s.adjoint_steps, s.adjoint_residual_evaluations,
        s.adjoint_jacobian_evaluations, s.checkpoints})
    w.raw(v);
  w.str(s.error_test), w.raw(s.max_order), w.raw(s.adjoint_wall_seconds), w.raw(s.wall_seconds);
}
IdasStats get_idas(Reader& rd) {
  IdasStats s;
  s.ok = rd.raw<bool>(), s.message = rd.str();
  for (long* v : {&s.steps, &s.residual_evaluations, &s.jacobian_evaluations,
                  &s.nonlinear_iterations, &s.error_test_failures,
                  &s.nonlinear_convergence_failures, &s.sensitivity_residual_evaluations,
                  &s.massless_velocities, &s.adjoint_problems, &s.adjoint_steps,
                  &s.adjoint_residual_evaluations, &s.adjoint_jacobian_evaluations, &s.checkpoints})
    *v = rd.raw<long>();
  s.error_test = rd.str(), s.max_order = rd.raw<int>();
  s.adjoint_wall_seconds = rd.raw<double>(), s.wall_seconds = rd.raw<double>();
  return s;
}

}  // namespace

std::string to_wire(const SensitivityResult& r) {
  Writer w;
  w.raw(r.ok), w.raw(r.interrupted), w.str(r.message);
  w.raw(static_cast<uint64_t>(r.warnings.size()));
  for (const auto& s : r.warnings) w.str(s);
  w.raw(static_cast<uint64_t>(r.responses.size()));
  for (const auto& x : r.responses) put(w, x);
  const SensitivityCounts& c = r.counts;
  for (long v : {c.simulations, c.steps, c.newton_iterations, c.factorizations,
                 c.residual_evaluations, c.pseudo_load_residuals, c.element_pseudo_loads,
                 c.mass_damping_products, c.back_solves, c.back_solve_rhs,
                 c.sensitivity_matrix_assemblies, c.refinement_solves, c.sensitivity_factorizations,
                 c.predictor_matrix_steps, c.adjoint_solves, c.adjoint_recomputed_steps})
    w.raw(v);
  w.raw(c.wall_seconds), w.raw(c.primal_wall_seconds), w.raw(c.adjoint_memory_bytes);
  put(w, r.primal);
  put(w, r.idas);
  w.raw(static_cast<uint64_t>(r.quadratures.size()));
  for (const auto& q : r.quadratures) {
    w.str(q.name), w.str(q.definition), w.raw(q.t0), w.raw(q.t1), w.raw(q.value);
    w.doubles(q.gradient.data(), static_cast<size_t>(q.gradient.size()));
  }
  return std::move(w.out);
}

SensitivityResult sensitivity_result_from_wire(const std::string& bytes) {
  Reader rd(bytes);
  SensitivityResult r;
  r.ok = rd.raw<bool>(), r.interrupted = rd.raw<bool>(), r.message = rd.str();
  for (auto n = rd.raw<uint64_t>(); n > 0; --n) r.warnings.push_back(rd.str());
  for (auto n = rd.raw<uint64_t>(); n > 0; --n) r.responses.push_back(get_response(rd));
  SensitivityCounts& c = r.counts;
  for (long* v :
       {&c.simulations, &c.steps, &c.newton_iterations, &c.factorizations, &c.residual_evaluations,
        &c.pseudo_load_residuals, &c.element_pseudo_loads, &c.mass_damping_products, &c.back_solves,
        &c.back_solve_rhs, &c.sensitivity_matrix_assemblies, &c.refinement_solves,
        &c.sensitivity_factorizations, &c.predictor_matrix_steps, &c.adjoint_solves,
        &c.adjoint_recomputed_steps})
    *v = rd.raw<long>();
  c.wall_seconds = rd.raw<double>(), c.primal_wall_seconds = rd.raw<double>();
  c.adjoint_memory_bytes = rd.raw<double>();
  r.primal = get_summary(rd);
  r.idas = get_idas(rd);
  for (auto n = rd.raw<uint64_t>(); n > 0; --n) {
    QuadratureResponse q;
    q.name = rd.str(), q.definition = rd.str();
    q.t0 = rd.raw<double>(), q.t1 = rd.raw<double>(), q.value = rd.raw<double>();
    const auto g = rd.vec();
    q.gradient =
        Eigen::Map<const Eigen::RowVectorXd>(g.data(), static_cast<Eigen::Index>(g.size()));
    r.quadratures.push_back(std::move(q));
  }
  return r;
}

std::string to_wire(const std::vector<ResponseSensitivity>& r) {
  Writer w;
  w.raw(static_cast<uint64_t>(r.size()));
  for (const auto& x : r) put(w, x);
  return std::move(w.out);
}

std::vector<ResponseSensitivity> responses_from_wire(const std::string& bytes) {
  Reader rd(bytes);
  std::vector<ResponseSensitivity> r;
  for (auto n = rd.raw<uint64_t>(); n > 0; --n) r.push_back(get_response(rd));
  return r;
}

}  // namespace lsmbs
