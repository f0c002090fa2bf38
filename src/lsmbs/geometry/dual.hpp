#pragma once
// Dual — forward-mode derivative of a scalar with respect to up to kMaxFeatureParams feature
// parameters. Features are written once as templates over the scalar type; evaluating them
// with Dual gives exact ∂φ/∂p and ∂(∇φ)/∂p for the volume-fraction derivatives.
#include <array>
#include <cmath>

namespace lsmbs {

inline constexpr int kMaxFeatureParams = 8;

struct Dual {
  double v = 0;
  std::array<double, kMaxFeatureParams> d{};
  Dual() = default;
  Dual(double value) : v(value) {}  // NOLINT: constants promote implicitly
  static Dual variable(double value, int i) {
    Dual x(value);
    x.d[i] = 1;
    return x;
  }
};

inline Dual apply(const Dual& a, double value, double da) {  // chain rule f(a)
  Dual r(value);
  for (int i = 0; i < kMaxFeatureParams; ++i) r.d[i] = da * a.d[i];
  return r;
}
inline Dual operator+(const Dual& a, const Dual& b) {
  Dual r(a.v + b.v);
  for (int i = 0; i < kMaxFeatureParams; ++i) r.d[i] = a.d[i] + b.d[i];
  return r;
}
inline Dual operator-(const Dual& a, const Dual& b) {
  Dual r(a.v - b.v);
  for (int i = 0; i < kMaxFeatureParams; ++i) r.d[i] = a.d[i] - b.d[i];
  return r;
}
inline Dual operator-(const Dual& a) { return apply(a, -a.v, -1); }
inline Dual operator*(const Dual& a, const Dual& b) {
  Dual r(a.v * b.v);
  for (int i = 0; i < kMaxFeatureParams; ++i) r.d[i] = a.d[i] * b.v + a.v * b.d[i];
  return r;
}
inline Dual operator/(const Dual& a, const Dual& b) {
  Dual r(a.v / b.v);
  for (int i = 0; i < kMaxFeatureParams; ++i) r.d[i] = (a.d[i] * b.v - a.v * b.d[i]) / (b.v * b.v);
  return r;
}
inline Dual sqrt(const Dual& a) {
  const double s = std::sqrt(a.v);
  return apply(a, s, s > 0 ? 0.5 / s : 0.0);
}
inline Dual abs(const Dual& a) { return a.v < 0 ? -a : a; }
inline Dual exp(const Dual& a) {
  const double e = std::exp(a.v);
  return apply(a, e, e);
}
inline Dual log(const Dual& a) { return apply(a, std::log(a.v), 1 / a.v); }
inline Dual cos(const Dual& a) { return apply(a, std::cos(a.v), -std::sin(a.v)); }
inline Dual sin(const Dual& a) { return apply(a, std::sin(a.v), std::cos(a.v)); }
/// |a|^e for a ≥ 0 with a possibly-dual exponent: exp(e log a), and 0 at a = 0.
inline Dual pow(const Dual& a, const Dual& e) {
  if (a.v <= 0) return Dual(0.0);
  return exp(e * log(a));
}
inline double value(const Dual& a) { return a.v; }
inline double value(double a) { return a; }
using std::abs;
using std::cos;
using std::exp;
using std::log;
using std::sin;
using std::sqrt;
inline double pow(double a, double e) { return a <= 0 ? 0.0 : std::pow(a, e); }

}  // namespace lsmbs
