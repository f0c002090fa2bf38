#include "lsmbs/sensitivity/response_quadrature.hpp"

#include <algorithm>
#include <cmath>

namespace lsmbs {

ResponseQuadrature::ResponseQuadrature(const Study& cs, std::vector<ParamDirection> directions,
                                       const ModelParams& params, double t_start, double t_end)
    : cs_(cs),
      tracker_(cs, directions, params),
      t_start_(t_start),
      t_end_(t_end),
      nv_(static_cast<int>(directions.size())) {
  using K = ResponseSpec::Kind;
  for (size_t r = 0; r < cs.responses.size(); ++r) {
    const auto& rs = cs.responses[r];
    if (rs.kind != K::kIntegral && rs.kind != K::kAverage && rs.kind != K::kAverageEq45 &&
        rs.kind != K::kRms)
      continue;
    const double a = std::max(rs.t0, t_start), b = std::min(rs.t1, t_end);
    if (!(b > a)) continue;  // empty window: no integral
    responses_.push_back({r, rs.kind == K::kRms, a, b});
  }
}

std::vector<double> ResponseQuadrature::breakpoints() const {
  std::vector<double> t;
  for (const auto& it : responses_) t.push_back(it.a), t.push_back(it.b);
  return t;
}

void ResponseQuadrature::integrand(const State& s, const ModelParams& p, double* g) {
  for (size_t k = 0; k < responses_.size(); ++k) {
    const double f = tracker_.response_measure(responses_[k].response, s, p, nullptr, nullptr,
                                               nullptr, nullptr, nullptr);
    g[k] = responses_[k].square ? f * f : f;
  }
}

void ResponseQuadrature::integrand_sensitivity(const State& s, const ModelParams& p, const Mat& dq,
                                               const Mat& dv, const Mat& da, const Mat& dl,
                                               Mat& dg) {
  dg.resize(size(), nv_);
  for (size_t k = 0; k < responses_.size(); ++k) {
    const double f =
        tracker_.response_measure(responses_[k].response, s, p, &dq, &dv, &da, &dl, &row_);
    dg.row(static_cast<Eigen::Index>(k)) = responses_[k].square ? (2 * f * row_).eval() : row_;
  }
}

bool ResponseQuadrature::integrand_gradient(int k, const State& s, const ModelParams& p, Vec& gq,
                                            Vec& gv, Eigen::RowVectorXd& gp, std::string& why) {
  const Item& it = responses_[static_cast<size_t>(k)];
  const double f = tracker_.response_partials(it.response, s, p, partials_, gp);
  if (!partials_.da.empty() || !partials_.dl.empty()) {
    why = "response '" + cs_.responses[it.response].name + "' measures " +
          cs_.measure_columns()[cs_.responses[it.response].column] +
          ", which depends on accelerations or constraint forces: the adjoint path supports "
          "integrands of "
          "positions, velocities and parameters only";
    return false;
  }
  const double w = it.square ? 2 * f : 1.0;  // rms: g = f²
  gq.setZero(s.q.size());
  gv.setZero(s.q.size());
  for (const auto& [j, d] : partials_.dq) gq[j] += w * d;
  for (const auto& [j, d] : partials_.dv) gv[j] += w * d;
  gp *= w;
  return true;
}

bool ResponseQuadrature::needs_gradient(int k, double t) const {
  const Item& it = responses_[static_cast<size_t>(k)];
  auto same = [](double a, double b) {
    return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(a));
  };
  return !same(t, t_start_) && (same(t, it.a) || same(t, it.b));
}

void ResponseQuadrature::on_breakpoint(double t, const Vec& Q, const Mat* dQ) {
  at_[t] = {Q, dQ ? *dQ : Mat()};
}

std::vector<QuadratureResponse> ResponseQuadrature::results() const {
  // Q at time t: recorded at a breakpoint (exactly, or within round-off of the grid), 0 at the
  // start
  auto lookup = [&](double t, size_t k, bool grad) -> Eigen::RowVectorXd {
    if (std::abs(t - t_start_) <= 1e-12 * std::max(1.0, std::abs(t)))
      return Eigen::RowVectorXd::Zero(grad ? nv_ : 1);
    auto it = at_.lower_bound(t - 1e-9 * std::max(1.0, std::abs(t)));
    if (it == at_.end() || std::abs(it->first - t) > 1e-9 * std::max(1.0, std::abs(t)))
      return Eigen::RowVectorXd::Constant(grad ? nv_ : 1, NAN);  // not reached (failed run)
    const auto i = static_cast<Eigen::Index>(k);
    if (!grad) return Eigen::RowVectorXd::Constant(1, it->second.first[i]);
    if (!it->second.second.size()) return Eigen::RowVectorXd::Constant(nv_, NAN);
    return it->second.second.row(i);
  };
  const bool with_grad = nv_ > 0;
  std::vector<QuadratureResponse> out;
  for (size_t k = 0; k < responses_.size(); ++k) {
    const auto& it = responses_[k];
    const auto& rs = cs_.responses[it.response];
    const std::string measure = cs_.measure_columns()[rs.column];
    QuadratureResponse q;
    q.name = rs.name;
    q.t0 = it.a, q.t1 = it.b;
    double v = lookup(it.b, k, false)[0] - lookup(it.a, k, false)[0];
    Eigen::RowVectorXd g;
    if (with_grad) g = lookup(it.b, k, true) - lookup(it.a, k, true);
    const double L = it.b - it.a;
    using K = ResponseSpec::Kind;
    switch (rs.kind) {
      case K::kIntegral:
        q.definition = "Q(b) - Q(a), Q = integral of " + measure + " dt";
        break;
      case K::kRms:
        q.definition = "sqrt((Q(b) - Q(a)) / (b - a)), Q = integral of " + measure + "^2 dt";
        v = std::sqrt(v / L);
        if (with_grad) g = g / (2 * L * v);
        break;
      default:
        q.definition = "(Q(b) - Q(a)) / (b - a), Q = integral of " + measure + " dt";
        v /= L;
        if (with_grad) g /= L;
        break;
    }
    q.value = v;
    q.gradient = g;
    out.push_back(std::move(q));
  }
  return out;
}

}  // namespace lsmbs
