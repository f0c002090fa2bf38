#include "lsmbs/geometry/bspline.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lsmbs {
namespace {

// Samples per span for the start of the closest-point search: a span's distance function has
// one minimum between two samples for every x closer than the span's radius of curvature.
constexpr int kSamples = 8;

double box_distance2(const Vec2& x, const std::array<Vec2, 2>& b) {
  const Vec2 y = x.cwiseMax(b[0]).cwiseMin(b[1]);
  return (x - y).squaredNorm();
}

// Whether segments ab and cd cross (touching counts).
bool segments_cross(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const auto orient = [](const Vec2& p, const Vec2& q, const Vec2& r) {
    const double v = (q.x() - p.x()) * (r.y() - p.y()) - (q.y() - p.y()) * (r.x() - p.x());
    return (v > 0) - (v < 0);
  };
  const int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  return o1 != o2 && o3 != o4;
}

}  // namespace

ClosedBSpline::ClosedBSpline(const double* th, int n) {
  P_.reserve(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) P_.emplace_back(th[2 * i], th[2 * i + 1]);
  samples_ = polygon(kSamples);
  double area2 = 0;
  for (size_t k = 0; k < samples_.size(); ++k) {
    const Vec2& a = samples_[k];
    const Vec2& b = samples_[(k + 1) % samples_.size()];
    area2 += a.x() * b.y() - b.x() * a.y();
  }
  ccw_ = area2 >= 0;
  box_.resize(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) {
    Vec2 lo = P_[static_cast<size_t>(k)], hi = lo;
    for (int i = 1; i < 4; ++i) {
      const Vec2& q = P_[static_cast<size_t>((k + i) % n)];
      lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
    }
    box_[static_cast<size_t>(k)] = {lo, hi};
  }
}

void ClosedBSpline::basis(double t, std::array<int, 4>& idx, std::array<double, 4>& N,
                          std::array<double, 4>* dN, std::array<double, 4>* ddN) const {
  const int n = size();
  int k = static_cast<int>(std::floor(t));
  double u = t - k;
  if (u >= 1) k += 1, u = 0;  // round-off at a knot
  k = ((k % n) + n) % n;
  for (int i = 0; i < 4; ++i) idx[static_cast<size_t>(i)] = (k + i) % n;
  const double w = 1 - u, u2 = u * u, u3 = u2 * u;
  N = {w * w * w / 6, (3 * u3 - 6 * u2 + 4) / 6, (-3 * u3 + 3 * u2 + 3 * u + 1) / 6, u3 / 6};
  if (dN) *dN = {-w * w / 2, (3 * u2 - 4 * u) / 2, (-3 * u2 + 2 * u + 1) / 2, u2 / 2};
  if (ddN) *ddN = {w, 3 * u - 2, 1 - 3 * u, u};
}

void ClosedBSpline::eval(double t, Vec2& c, Vec2& d1, Vec2& d2) const {
  std::array<int, 4> idx;
  std::array<double, 4> N, dN, ddN;
  basis(t, idx, N, &dN, &ddN);
  c.setZero(), d1.setZero(), d2.setZero();
  for (size_t i = 0; i < 4; ++i) {
    const Vec2& q = P_[static_cast<size_t>(idx[i])];
    c += N[i] * q, d1 += dN[i] * q, d2 += ddN[i] * q;
  }
}

Vec2 ClosedBSpline::point(double t) const {
  Vec2 c, d1, d2;
  eval(t, c, d1, d2);
  return c;
}

std::vector<Vec2> ClosedBSpline::polygon(int per_span) const {
  std::vector<Vec2> out;
  out.reserve(static_cast<size_t>(size() * per_span));
  for (int k = 0; k < size(); ++k)
    for (int j = 0; j < per_span; ++j) out.push_back(point(k + static_cast<double>(j) / per_span));
  return out;
}

void ClosedBSpline::eval_span(int k, double u, Vec2& c, Vec2& d1, Vec2& d2) const {
  const int n = size();
  const Vec2 &p0 = P_[static_cast<size_t>(k)], &p1 = P_[static_cast<size_t>((k + 1) % n)],
             &p2 = P_[static_cast<size_t>((k + 2) % n)], &p3 = P_[static_cast<size_t>((k + 3) % n)];
  const double w = 1 - u, u2 = u * u, u3 = u2 * u;
  c = (w * w * w * p0 + (3 * u3 - 6 * u2 + 4) * p1 + (-3 * u3 + 3 * u2 + 3 * u + 1) * p2 +
       u3 * p3) /
      6;
  d1 = (-w * w * p0 + (3 * u2 - 4 * u) * p1 + (-3 * u2 + 2 * u + 1) * p2 + u2 * p3) / 2;
  d2 = w * p0 + (3 * u - 2) * p1 + (1 - 3 * u) * p2 + u * p3;
}

// The minimum of |C(k + u) − x|² over u ∈ [0, 1]: from u0 (< 0: the nearest of the span's
// samples), Newton on f(u) = ½|C − x|² (f' = (C − x)·C', f'' = |C'|² + (C − x)·C''), kept in the
// span and, where f'' ≤ 0, a gradient step of a sample's width.
double ClosedBSpline::local_min(const Vec2& x, int k, double u0, double* dist2) const {
  const int n = size();
  double u = u0;
  if (u < 0) {
    double best = std::numeric_limits<double>::infinity();
    for (int j = 0; j <= kSamples; ++j) {
      const Vec2& s = samples_[static_cast<size_t>((k * kSamples + j) % (n * kSamples))];
      if (const double d2 = (s - x).squaredNorm(); d2 < best) best = d2, u = double(j) / kSamples;
    }
  }
  Vec2 c, d1, d2;
  for (int it = 0; it < 40; ++it) {
    eval_span(k, u, c, d1, d2);
    const Vec2 r = c - x;
    const double g = r.dot(d1), h = d1.squaredNorm() + r.dot(d2);
    double step = h > 0 ? -g / h : (g > 0 ? -1.0 : 1.0) / kSamples;
    const double un = std::clamp(u + step, 0.0, 1.0);
    step = un - u;
    u = un;
    if (std::abs(step) < 1e-15) break;
  }
  eval_span(k, u, c, d1, d2);
  *dist2 = (c - x).squaredNorm();
  return k + u;
}

ClosedBSpline::Foot ClosedBSpline::closest(const Vec2& x) const {
  const int n = size(), m = n * kSamples;
  // the nearest sample starts Newton in its span (and the span before it at a knot); then every
  // span whose control-point box (it holds the span: convex hull property) is nearer than the
  // best distance so far is searched too
  int js = 0;
  double ds = std::numeric_limits<double>::infinity();
  for (int j = 0; j < m; ++j)
    if (const double d2 = (samples_[static_cast<size_t>(j)] - x).squaredNorm(); d2 < ds)
      ds = d2, js = j;
  const int first = js / kSamples;
  double best2 = 0;
  double t = local_min(x, first, double(js % kSamples) / kSamples, &best2);
  const int before = js % kSamples == 0 ? (first + n - 1) % n : -1;
  if (before >= 0) {
    double d2 = 0;
    const double tk = local_min(x, before, 1.0, &d2);
    if (d2 < best2) best2 = d2, t = tk;
  }
  for (int k = 0; k < n; ++k) {
    if (k == first || k == before || box_distance2(x, box_[static_cast<size_t>(k)]) >= best2)
      continue;
    double d2 = 0;
    const double tk = local_min(x, k, -1, &d2);
    if (d2 < best2) best2 = d2, t = tk;
  }
  if (t >= n) t -= n;
  Vec2 c, d1, d2;
  const int k = std::min(static_cast<int>(t), n - 1);
  eval_span(k, t - k, c, d1, d2);
  Foot f;
  f.t = t;
  const double speed = d1.norm();
  f.normal = (ccw_ ? Vec2(d1.y(), -d1.x()) : Vec2(-d1.y(), d1.x())) / speed;
  const double dist = std::sqrt(best2);
  f.distance = (x - c).dot(f.normal) >= 0 ? dist : -dist;
  return f;
}

std::string ClosedBSpline::check() const {
  if (size() < 4) return "a closed B-spline needs at least 4 control points";
  for (const Vec2& q : P_)
    if (!std::isfinite(q.x()) || !std::isfinite(q.y())) return "a control point is not finite";
  const auto poly = polygon(kSamples);
  double scale = 0;
  for (const Vec2& q : P_) scale = std::max(scale, (q - P_[0]).norm());
  if (!(scale > 0)) return "every control point is at the same place";
  for (int k = 0; k < size() * kSamples; ++k) {
    Vec2 c, d1, d2;
    eval(static_cast<double>(k) / kSamples, c, d1, d2);
    if (d1.norm() < 1e-9 * scale)
      return "the curve has a cusp near control point " + std::to_string(k / kSamples + 1) +
             " (control points that coincide)";
  }
  const size_t m = poly.size();
  for (size_t i = 0; i < m; ++i)
    for (size_t j = i + 2; j < m; ++j) {
      if (i == 0 && j == m - 1) continue;  // neighbours through the closing segment
      if (segments_cross(poly[i], poly[(i + 1) % m], poly[j], poly[(j + 1) % m]))
        return "the curve crosses itself (spans " + std::to_string(i / kSamples + 1) + " and " +
               std::to_string(j / kSamples + 1) + ")";
    }
  return {};
}

}  // namespace lsmbs
