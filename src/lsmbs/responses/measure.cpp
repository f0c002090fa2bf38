#include "lsmbs/responses/measure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lsmbs {
namespace {
Vec2 point_position(const PointRef& p, const Vec& q) {
  double buf[3] = {0, 0, 0};
  for (int i = 0; i < p.num_dofs(); ++i) buf[i] = q[p.dof0 + i];
  return PointKinematics::position(p, buf);
}
}  // namespace

void PositionMeasure::evaluate(const Model&, const State& s, const ModelParams&, double* out) const {
  const Vec2 x = point_position(pt_, s.q);
  out[0] = x.x();
  out[1] = x.y();
}

void DistanceMeasure::evaluate(const Model&, const State& s, const ModelParams&, double* out) const {
  *out = (point_position(b_, s.q) - point_position(a_, s.q)).norm() - ref_;
}

Vec2 ChainPath::at(double t) const {
  Vec2 x = origin;
  double phi = 0;
  for (const auto& l : links) {
    phi = (l.relative ? phi : 0.0) + l.law->value(t);
    x += l.length * Vec2(std::cos(phi), std::sin(phi));
  }
  return x;
}

void PathDeviationMeasure::evaluate(const Model&, const State& s, const ModelParams&, double* out) const {
  *out = (path_.at(s.t) - point_position(pt_, s.q)).norm();
}

std::vector<std::string> ConstraintForceMeasure::components() const {
  std::vector<std::string> c;
  for (size_t i = 0; i < rows_.size(); ++i) c.push_back(name() + "." + std::to_string(i));
  return c;
}

void ConstraintForceMeasure::evaluate(const Model&, const State& s, const ModelParams&, double* out) const {
  for (size_t i = 0; i < rows_.size(); ++i) out[i] = k_ * s.lambda[rows_[i]];
}

const char* ResponseSpec::kind_name(Kind k) {
  switch (k) {
    case Kind::kAverage: return "average";
    case Kind::kAverageEq45: return "average_eq45";
    case Kind::kMax: return "max";
    case Kind::kMin: return "min";
    case Kind::kFinal: return "final";
    case Kind::kIntegral: return "integral";
    case Kind::kRms: return "rms";
  }
  return "?";
}

double aggregate(const ResponseSpec& r, const std::vector<double>& t, const std::vector<double>& v, int* count) {
  const double eps = 1e-9 * (t.size() > 1 ? std::abs(t[1] - t[0]) : 1.0);
  double acc = 0, best_max = -std::numeric_limits<double>::infinity(),
         best_min = std::numeric_limits<double>::infinity(), last = NAN;
  int n = 0;
  double prev_t = NAN, prev_v = NAN;
  for (size_t i = 0; i < t.size(); ++i) {
    if (t[i] < r.t0 - eps || t[i] > r.t1 + eps) continue;
    ++n;
    switch (r.kind) {
      case ResponseSpec::Kind::kAverage:
      case ResponseSpec::Kind::kAverageEq45: acc += v[i]; break;
      case ResponseSpec::Kind::kRms: acc += v[i] * v[i]; break;
      case ResponseSpec::Kind::kIntegral:
        if (n > 1) acc += 0.5 * (t[i] - prev_t) * (v[i] + prev_v);
        break;
      default: break;
    }
    best_max = std::max(best_max, v[i]);
    best_min = std::min(best_min, v[i]);
    last = v[i];
    prev_t = t[i];
    prev_v = v[i];
  }
  if (count) *count = n;
  if (n == 0) return NAN;
  switch (r.kind) {
    case ResponseSpec::Kind::kAverage: return acc / n;
    case ResponseSpec::Kind::kAverageEq45: return n > 1 ? acc / (n - 1) : NAN;
    case ResponseSpec::Kind::kRms: return std::sqrt(acc / n);
    case ResponseSpec::Kind::kIntegral: return acc;
    case ResponseSpec::Kind::kMax: return best_max;
    case ResponseSpec::Kind::kMin: return best_min;
    case ResponseSpec::Kind::kFinal: return last;
  }
  return NAN;
}

}  // namespace lsmbs
