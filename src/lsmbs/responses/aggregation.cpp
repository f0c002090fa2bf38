#include "lsmbs/responses/aggregation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lsmbs {

std::string ResponseSpec::unit(Kind k, const std::string& u) {
  if (k != Kind::kIntegral) return u;
  if (u == "1") return "s";
  if (u.size() > 2 && u.compare(u.size() - 2, 2, "/s") == 0) return u.substr(0, u.size() - 2);
  return u + "*s";
}

const char* ResponseSpec::kind_name(Kind k) {
  switch (k) {
    case Kind::kAverage:
      return "average";
    case Kind::kAverageEq45:
      return "average_eq45";
    case Kind::kMax:
      return "max";
    case Kind::kMin:
      return "min";
    case Kind::kFinal:
      return "final";
    case Kind::kIntegral:
      return "integral";
    case Kind::kRms:
      return "rms";
    case Kind::kPerStep:
      return "per_step";
    case Kind::kKS:
      return "ks";
  }
  return "?";
}

double Aggregate::scalar() const {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  return values.size() == 1 ? values[0] : *std::max_element(values.begin(), values.end());
}

Aggregate aggregate(const ResponseSpec& r, const std::vector<double>& t,
                    const std::vector<double>& v, const Mat* G) {
  using K = ResponseSpec::Kind;
  Aggregate out;
  const double eps = 1e-9 * (t.size() > 1 ? std::abs(t[1] - t[0]) : 1.0);
  std::vector<Eigen::Index> idx;
  for (size_t i = 0; i < t.size(); ++i)
    if (t[i] >= r.t0 - eps && t[i] <= r.t1 + eps) idx.push_back(static_cast<Eigen::Index>(i));
  const Eigen::Index nv = G ? G->cols() : 0;
  const auto n = static_cast<Eigen::Index>(idx.size());
  out.count = static_cast<int>(n);
  if (n == 0) {
    out.gradient.setZero(0, nv);
    return out;
  }
  if (r.kind == K::kPerStep) {
    out.gradient.setZero(n, nv);
    for (Eigen::Index k = 0; k < n; ++k) {
      out.values.push_back(v[idx[k]]);
      out.times.push_back(t[idx[k]]);
      if (nv) out.gradient.row(k) = G->row(idx[k]);
    }
    return out;
  }
  // the scalar kinds: the value, its derivative with respect to each step's value f_n (the
  // weights w_n) and the gradient Σ_n w_n df_n/dp
  out.weights.assign(t.size(), 0.0);
  out.gradient.setZero(1, nv);
  auto add_row = [&](double w, Eigen::Index i) {
    out.weights[i] += w;
    if (nv) out.gradient.row(0) += w * G->row(i);
  };
  double val = 0;
  switch (r.kind) {
    case K::kAverage:
    case K::kAverageEq45: {
      // eq. (45): the sum over the window's steps divided by their number (average) or by the
      // number of intervals n_cvf − n_cvi as printed (average_eq45; undefined for one step)
      const double div = r.kind == K::kAverage
                             ? static_cast<double>(n)
                             : (n > 1 ? n - 1.0 : std::numeric_limits<double>::quiet_NaN());
      for (auto i : idx) val += v[i], add_row(1, i);
      val /= div;
      out.gradient /= div;
      for (auto& w : out.weights) w /= div;
      break;
    }
    case K::kRms: {
      for (auto i : idx) val += v[i] * v[i];
      val = std::sqrt(val / n);
      if (val > 0)
        for (auto i : idx) add_row(v[i] / (n * val), i);  // d sqrt(S/n) = (1/(n rms)) Σ f_n df_n
      break;
    }
    case K::kIntegral:
      for (Eigen::Index k = 1; k < n; ++k) {
        const double w = 0.5 * (t[idx[k]] - t[idx[k - 1]]);
        val += w * (v[idx[k]] + v[idx[k - 1]]);
        add_row(w, idx[k]);
        add_row(w, idx[k - 1]);
      }
      break;
    case K::kMax:
    case K::kMin: {
      Eigen::Index best = idx[0];
      for (auto i : idx)
        if (r.kind == K::kMax ? v[i] > v[best] : v[i] < v[best]) best = i;
      val = v[best];
      out.extreme_time = t[best];
      add_row(1, best);  // a subgradient: the extreme step's derivative
      break;
    }
    case K::kFinal:
      val = v[idx.back()];
      add_row(1, idx.back());
      break;
    case K::kKS: {
      double m = v[idx[0]];
      for (auto i : idx) m = std::max(m, v[i]);
      double sum = 0;
      for (auto i : idx) sum += std::exp(r.ks * (v[i] - m));
      val = m + std::log(sum) / r.ks;
      for (auto i : idx) add_row(std::exp(r.ks * (v[i] - m)) / sum, i);  // softmax weights
      break;
    }
    case K::kPerStep:
      break;  // handled above
  }
  out.values.push_back(val);
  return out;
}

}  // namespace lsmbs
