#include "lsmbs/geometry/length_scale_parts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

namespace lsmbs::length_scale_parts {

QuarterArc::QuarterArc(double a_, double b_, double xi_, double eta_)
    : a(a_), b(b_), xi(xi_), eta(eta_) {
  for (int k = 0; k <= kPoints; ++k) table[static_cast<size_t>(k)] = at(k * step());
}

double QuarterArc::step() { return 0.5 * std::numbers::pi / kPoints; }

Vec2 QuarterArc::at(double t) const {
  return Vec2(a * std::pow(std::cos(t), 2 / xi), b * std::pow(std::sin(t), 2 / eta));
}

Vec2 QuarterArc::foot(const Vec2& y) const {
  int best = 0;
  double bd = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= kPoints; ++k) {
    const double d = (table[static_cast<size_t>(k)] - y).squaredNorm();
    if (d < bd) bd = d, best = k;
  }
  double lo = std::max(0, best - 1) * step(), hi = std::min(kPoints, best + 1) * step();
  const double r = 0.5 * (std::sqrt(5.0) - 1);
  double t1 = hi - r * (hi - lo), t2 = lo + r * (hi - lo);
  double f1 = (at(t1) - y).squaredNorm(), f2 = (at(t2) - y).squaredNorm();
  for (int it = 0; it < 48; ++it) {
    if (f1 < f2) {
      hi = t2, t2 = t1, f2 = f1;
      t1 = hi - r * (hi - lo), f1 = (at(t1) - y).squaredNorm();
    } else {
      lo = t1, t1 = t2, f1 = f2;
      t2 = lo + r * (hi - lo), f2 = (at(t2) - y).squaredNorm();
    }
  }
  return at(0.5 * (lo + hi));
}

QuarterArc arc_of(Feature::Type type, const std::vector<double>& th) {
  return type == Feature::Type::kSuperEllipse ? QuarterArc(th[2], th[3], th[4], th[5])
                                              : QuarterArc(0, 0, 1, 1);
}

template <class T>
T shape_distance(const Feature& f, const Vec2& x, const T* th, const QuarterArc* arc) {
  if (f.type() != Feature::Type::kSuperEllipse) {  // exact already (eq. 41; a circle)
    const T D = f.distance<T>(x, th);
    return f.hole() ? D : -D;
  }
  const double a = value(th[2]), b = value(th[3]), xi = value(th[4]), eta = value(th[5]);
  const double ang = value(th[6]), c = std::cos(ang), sn = std::sin(ang);
  const double dx = x.x() - value(th[0]), dy = x.y() - value(th[1]);
  const double u = c * dx + sn * dy, v = c * dy - sn * dx;
  std::optional<QuarterArc> own;  // tabulated only when the caller has no table of this design
  if (!arc) own.emplace(a, b, xi, eta);
  Vec2 foot = (arc ? *arc : *own).foot(Vec2(std::abs(u), std::abs(v)));
  foot = Vec2(std::copysign(foot.x(), u), std::copysign(foot.y(), v));
  const bool inside = std::pow(std::abs(u / a), xi) + std::pow(std::abs(v / b), eta) < 1;
  const double dist = (Vec2(u, v) - foot).norm();
  const T yx(value(th[0]) + c * foot.x() - sn * foot.y());
  const T yy(value(th[1]) + sn * foot.x() + c * foot.y());
  T phi, gx, gy;
  f.phi_grad(yx, yy, th, phi, gx, gy);
  const double g = std::hypot(value(gx), value(gy));
  return T(inside ? -dist : dist) + (phi - T(value(phi))) / g;
}

template double shape_distance<double>(const Feature&, const Vec2&, const double*,
                                       const QuarterArc*);
template Dual shape_distance<Dual>(const Feature&, const Vec2&, const Dual*, const QuarterArc*);

Vec2 centre(const Feature& f, const std::vector<double>& th) {
  if (f.type() != Feature::Type::kBSpline) return {th[0], th[1]};
  Vec2 c = Vec2::Zero();
  for (size_t i = 0; i + 1 < th.size(); i += 2) c += Vec2(th[i], th[i + 1]);
  return c / static_cast<double>(th.size() / 2);
}

double reach(const Feature& f, const std::vector<double>& th) {
  switch (f.type()) {
    case Feature::Type::kCircle:
      return th[2];
    case Feature::Type::kEllipse:
      return th[4] * std::max(th[2], th[3]);
    case Feature::Type::kSuperEllipse:
      return std::hypot(th[2], th[3]);
    case Feature::Type::kBSpline: {
      const Vec2 c = centre(f, th);
      double r = 0;
      for (size_t i = 0; i + 1 < th.size(); i += 2)
        r = std::max(r, (Vec2(th[i], th[i + 1]) - c).norm());
      return r;
    }
  }
  return std::numeric_limits<double>::infinity();
}

double ks_min(const std::vector<double>& v, double rho, std::vector<double>& w) {
  const double m = *std::min_element(v.begin(), v.end());
  w.resize(v.size());
  double sum = 0;
  for (size_t k = 0; k < v.size(); ++k) sum += w[k] = std::exp(-rho * (v[k] - m));
  for (double& x : w) x /= sum;
  return m - std::log(sum) / rho;
}

SampledMinimum sampled_minimum(const std::vector<double>& di, const std::vector<double>* dj,
                               const std::vector<char>& use, double cap, double rho) {
  SampledMinimum r;
  std::vector<double> v;
  std::vector<size_t> at;
  for (size_t k = 0; k < di.size(); ++k) {
    if (!use.empty() && !use[k]) continue;
    const double x = di[k] + (dj ? (*dj)[k] : 0);
    if (x < cap) v.push_back(x), at.push_back(k);
  }
  if (v.empty()) return r;
  std::vector<double> w;
  r.any = true;
  r.value = ks_min(v, rho, w);
  r.argmin = at[static_cast<size_t>(std::min_element(v.begin(), v.end()) - v.begin())];
  for (size_t q = 0; q < v.size(); ++q)
    if (w[q] >= 1e-16) r.weights.emplace_back(at[q], w[q]);
  return r;
}

LengthScaleConstraint member_size(const std::string& name, Feature::Type type,
                                  const std::vector<ParamBinding>& params,
                                  const std::vector<double>& th, double delta, double tolerance,
                                  int nv) {
  LengthScaleConstraint c;
  c.kind = "member", c.first = name, c.bound = delta;
  c.gradient = Vec::Zero(nv);
  c.at = Vec2(th[0], th[1]);
  auto add = [&](int m, double dv) {  // ∂c/∂θ_m = dv
    const ParamBinding& b = params[static_cast<size_t>(m)];
    if (b.variable >= 0) c.gradient[b.variable] += dv * b.scale;
  };
  if (type == Feature::Type::kCircle) {
    c.value = 2 * th[2];
    add(2, 2);
    return c;
  }
  const double d = type == Feature::Type::kEllipse ? th[4] : 1.0;
  const std::vector<double> v = {2 * th[2] * d, 2 * th[3] * d};
  std::vector<double> w;
  const double rho = std::log(2.0) / (tolerance * delta);
  c.value = ks_min(v, rho, w);
  c.error_bound = tolerance * delta;
  add(2, 2 * d * w[0]);
  add(3, 2 * d * w[1]);
  if (type == Feature::Type::kEllipse) add(4, 2 * th[2] * w[0] + 2 * th[3] * w[1]);
  return c;
}

}  // namespace lsmbs::length_scale_parts
