#include "lsmbs/geometry/feature.hpp"

#include <cmath>
#include <stdexcept>
#include <type_traits>

#include "lsmbs/geometry/bspline.hpp"

namespace lsmbs {

Feature::Feature(std::string name, Type type, std::vector<ParamBinding> params, bool hole)
    : name_(std::move(name)), type_(type), params_(std::move(params)), hole_(hole) {}

const std::vector<std::string>& Feature::parameter_names(Type t) {
  static const std::vector<std::string> ellipse = {"cx", "cy", "a", "b", "d", "angle"};
  static const std::vector<std::string> super = {"cx", "cy", "a", "b", "xi", "eta", "angle"};
  static const std::vector<std::string> circle = {"cx", "cy", "r"};
  static const std::vector<std::string> none;
  return t == Type::kEllipse        ? ellipse
         : t == Type::kSuperEllipse ? super
         : t == Type::kCircle       ? circle
                                    : none;
}

std::string Feature::parameter_name(size_t i) const {
  if (type_ == Type::kBSpline) return (i % 2 ? "y" : "x") + std::to_string(i / 2 + 1);
  return parameter_names(type_).at(i);
}

Feature::Type Feature::parse_type(const std::string& s, bool* ok) {
  *ok = true;
  if (s == "ellipse") return Type::kEllipse;
  if (s == "super_ellipse") return Type::kSuperEllipse;
  if (s == "circle") return Type::kCircle;
  if (s == "bspline") return Type::kBSpline;
  *ok = false;
  return Type::kCircle;
}

std::vector<double> Feature::values(const Vec& p) const {
  std::vector<double> v;
  for (const auto& b : params_) v.push_back(b.value(p));
  return v;
}

bool Feature::exact_distance(const std::vector<double>& th) const {
  switch (type_) {
    case Type::kCircle:
    case Type::kBSpline:
      return true;
    case Type::kEllipse:
      return th[2] * th[4] > 0 && th[3] * th[4] > 0;
    case Type::kSuperEllipse:
      return false;
  }
  return false;
}

double Feature::far_bound(const Vec2& c, double rho, const std::vector<double>& th) const {
  if (type_ != Type::kSuperEllipse) return 0;
  const double a = th[2], b = th[3], xi = th[4], eta = th[5];
  const double cs = std::cos(th[6]), sn = std::sin(th[6]);
  const double dx = c.x() - th[0], dy = c.y() - th[1];
  // the disc is a disc of the same radius in the rotated frame: |u|, |v| lie in these intervals
  const double u = std::abs(cs * dx + sn * dy), v = std::abs(cs * dy - sn * dx);
  const double s_lo = std::max(0.0, u - rho) / a, s_hi = (u + rho) / a;
  const double t_lo = std::max(0.0, v - rho) / b, t_hi = (v + rho) / b;
  // φ = s^ξ + t^η − 1 and both |∂φ/∂u| = ξ s^(ξ−1)/a, |∂φ/∂v| = η t^(η−1)/b grow with s, t
  // (ξ, η ≥ 1); +1e-15 covers distance()'s regularization sqrt(|∇φ|² + 1e-30)
  const double g_hi =
      std::hypot(xi * std::pow(s_hi, xi - 1) / a, eta * std::pow(t_hi, eta - 1) / b);
  const double phi_lo = std::pow(s_lo, xi) + std::pow(t_lo, eta) - 1;
  const double phi_hi = std::pow(s_hi, xi) + std::pow(t_hi, eta) - 1;
  double L = 0;
  if (phi_lo > 0) {
    L = phi_lo / (g_hi + 1e-15);
  } else if (phi_hi < 0) {
    // inside; at the centre itself distance() returns −min(a, b) (∇φ = 0 there)
    L = -std::min(-phi_hi / (g_hi + 1e-15), std::min(a, b));
  }
  return hole_ ? L : -L;
}

std::string Feature::check(const std::vector<double>& th) const {
  for (double v : th)
    if (!std::isfinite(v)) return "a parameter is not finite";
  switch (type_) {
    case Type::kEllipse:
      if (!(th[2] > 0) || !(th[3] > 0)) return "semi-axis scales a and b must be positive";
      if (!(th[4] >= 0)) return "size d must be non-negative";
      break;
    case Type::kSuperEllipse:
      if (!(th[2] > 0) || !(th[3] > 0)) return "semi-axes a and b must be positive";
      if (!(th[4] >= 1) || !(th[5] >= 1)) return "exponents xi and eta must be >= 1";
      break;
    case Type::kCircle:
      if (!(th[2] >= 0)) return "radius r must be non-negative";
      break;
    case Type::kBSpline:
      if (th.size() % 2 || th.size() < 8)
        return "a closed B-spline needs at least 4 control points";
      return ClosedBSpline(th.data(), static_cast<int>(th.size() / 2)).check();
  }
  return {};
}

template <class T>
void Feature::phi_grad(const T& px, const T& py, const T* th, T& phi, T& gx, T& gy) const {
  using std::abs;
  if (type_ == Type::kBSpline) {
    if constexpr (std::is_same_v<T, double>) {
      const auto foot = ClosedBSpline(th, static_cast<int>(params_.size() / 2)).closest({px, py});
      phi = foot.distance, gx = foot.normal.x(), gy = foot.normal.y();
      return;
    } else {
      throw std::logic_error("Feature::phi_grad<Dual> of a B-spline (LevelSet evaluates it)");
    }
  }
  const T dx = px - th[0], dy = py - th[1];
  T u = dx, v = dy;
  T c(1.0), s(0.0);
  const int angle_index = type_ == Type::kEllipse ? 5 : type_ == Type::kSuperEllipse ? 6 : -1;
  if (angle_index >= 0) {
    c = cos(th[angle_index]);
    s = sin(th[angle_index]);
    u = c * dx + s * dy;
    v = c * dy - s * dx;
  }
  T gu(0.0), gv(0.0);  // gradient in the local frame
  const double tiny = 1e-300;
  switch (type_) {
    case Type::kEllipse: {
      const T a = th[2], b = th[3];
      const T r = sqrt(u * u / (a * a) + v * v / (b * b) + T(tiny));
      phi = r - th[4];
      gu = u / (a * a * r);
      gv = v / (b * b * r);
      break;
    }
    case Type::kSuperEllipse: {
      const T a = th[2], b = th[3], xi = th[4], eta = th[5];
      const T au = abs(u / a), av = abs(v / b);
      // |u/a|^ξ as |u/a|^(ξ−1)·|u/a|: two pow per point instead of four (the mapping's hot loop)
      const T pu = pow(au, xi - T(1.0)), pv = pow(av, eta - T(1.0));
      phi = pu * au + pv * av - T(1.0);
      const double su = value(u) < 0 ? -1.0 : 1.0, sv = value(v) < 0 ? -1.0 : 1.0;
      gu = xi * pu / a * T(su);
      gv = eta * pv / b * T(sv);
      break;
    }
    case Type::kCircle: {
      const T r = sqrt(u * u + v * v + T(tiny));
      phi = r - th[2];
      gu = u / r;
      gv = v / r;
      break;
    }
    case Type::kBSpline:  // returned above
      break;
  }
  gx = c * gu - s * gv;  // back to the global frame: ∇_x = R(angle) ∇_u
  gy = s * gu + c * gv;
}

namespace {

// Closest point of the ellipse (u/e0)² + (v/e1)² = 1 to (y0, y1), both in the first quadrant
// and e0 ≥ e1 > 0 (Eberly, "Distance from a point to an ellipse, an ellipsoid, or a
// hyperellipsoid", 2013: bisection on the root of the monotone secular function, robust for
// every point, inside or outside, slender or not).
void ellipse_closest_first_quadrant(double e0, double e1, double y0, double y1, double& x0,
                                    double& x1) {
  if (y1 > 0) {
    if (y0 > 0) {
      const double z0 = y0 / e0, z1 = y1 / e1, g = z0 * z0 + z1 * z1 - 1;
      if (g == 0) {
        x0 = y0, x1 = y1;
        return;
      }
      const double r0 = (e0 / e1) * (e0 / e1), n0 = r0 * z0;
      double s0 = z1 - 1, s1 = g < 0 ? 0 : std::hypot(n0, z1) - 1, sb = 0;
      for (int i = 0; i < 1100; ++i) {
        sb = 0.5 * (s0 + s1);
        if (sb == s0 || sb == s1) break;
        const double q0 = n0 / (sb + r0), q1 = z1 / (sb + 1), gg = q0 * q0 + q1 * q1 - 1;
        if (gg > 0)
          s0 = sb;
        else if (gg < 0)
          s1 = sb;
        else
          break;
      }
      x0 = r0 * y0 / (sb + r0);
      x1 = y1 / (sb + 1);
    } else {
      x0 = 0, x1 = e1;
    }
  } else {
    const double numer0 = e0 * y0, denom0 = e0 * e0 - e1 * e1;
    if (numer0 < denom0) {
      const double xde0 = numer0 / denom0;
      x0 = e0 * xde0;
      x1 = e1 * std::sqrt(std::max(0.0, 1 - xde0 * xde0));
    } else {
      x0 = e0, x1 = 0;
    }
  }
}

}  // namespace

template <class T>
T Feature::distance(const Vec2& x, const T* th, double refine_within, int foot_iterations) const {
  const T x0(x.x()), y0(x.y());
  T phi, gx, gy;
  if (type_ == Type::kBSpline) {  // exact already; outside the hot loops (LevelSet has its own)
    phi_grad(x0, y0, th, phi, gx, gy);
    return hole_ ? phi : -phi;
  }
  if (type_ == Type::kEllipse) {
    // eq. (41): the exact Euclidean distance to the ellipse with semi-axes a·d, b·d. Its
    // derivative with respect to every parameter θ follows from the closest point y* alone
    // (the envelope theorem): ∂D/∂θ = (∂φ/∂θ)(y*) / |∇φ(y*)|. The exact distance is monotone
    // in d, so μ(d) is monotone even for holes smaller than a sub-cell (the normalized φ/|∇φ| is
    // not, and a tiny slender hole's mass then had gradients of the wrong sign).
    const double A = value(th[2]) * value(th[4]), B = value(th[3]) * value(th[4]);
    if (A > 0 && B > 0) {
      const double ang = value(th[5]), c = std::cos(ang), sn = std::sin(ang);
      const double dx = x.x() - value(th[0]), dy = x.y() - value(th[1]);
      const double u = c * dx + sn * dy, v = c * dy - sn * dx;
      double cu, cv;
      if (A >= B) {
        ellipse_closest_first_quadrant(A, B, std::abs(u), std::abs(v), cu, cv);
      } else {
        ellipse_closest_first_quadrant(B, A, std::abs(v), std::abs(u), cv, cu);
      }
      cu = std::copysign(cu, u), cv = std::copysign(cv, v);
      const bool inside = (u / A) * (u / A) + (v / B) * (v / B) < 1;
      const double dist = std::hypot(u - cu, v - cv);
      const double d = inside ? -dist : dist;
      // φ and ∇φ at the closest point, carrying ∂/∂θ in T
      const T yx(value(th[0]) + c * cu - sn * cv), yy(value(th[1]) + sn * cu + c * cv);
      phi_grad(yx, yy, th, phi, gx, gy);
      const double g = std::sqrt(value(gx) * value(gx) + value(gy) * value(gy));
      const T D = T(d) + (phi - T(value(phi))) / g;
      return hole_ ? D : -D;
    }
  }
  phi_grad(x0, y0, th, phi, gx, gy);
  // A circle's φ = |x − c| − r is its exact signed distance, also at the centre, where ∇φ
  // vanishes and φ/|∇φ| was −r/1e-15 (a node at the centre of a hole smaller than the band then
  // had μ and dμ/dr of a far point)
  if (type_ == Type::kCircle) return hole_ ? phi : -phi;
  T g2 = gx * gx + gy * gy + T(1e-30);
  const T D0 = phi / sqrt(g2);
  if (type_ == Type::kSuperEllipse && value(gx) == 0 && value(gy) == 0) {
    // the centre (ξ, η > 1): ∇φ = 0 and φ/|∇φ| = −1e15; the distance to the nearest axis vertex,
    // min(a, b), is the true distance for ξ, η ≥ 2 and an upper bound otherwise. Near the centre
    // of a super-ellipse smaller than the refinement radius φ/|∇φ| still overestimates the
    // distance (docs/methods.md, "Level-set distances")
    const T D = value(th[2]) < value(th[3]) ? -th[2] : -th[3];
    return hole_ ? D : -D;
  }
  T D = D0;
  const double ad = std::abs(value(D0));
  if (ad < refine_within) {
    T px = x0, py = y0;
    for (int k = 0; k < 3; ++k) {
      px = px - phi * gx / g2;
      py = py - phi * gy / g2;
      phi_grad(px, py, th, phi, gx, gy);
      g2 = gx * gx + gy * gy + T(1e-30);
    }
    for (int it = 0; it < foot_iterations; ++it) {
      // along the tangent to the foot of x, then back onto φ = 0
      const T gn = sqrt(g2), tx = -gy / gn, ty = gx / gn;
      const T along = (x0 - px) * tx + (y0 - py) * ty;
      px = px + along * tx;
      py = py + along * ty;
      for (int k = 0; k < 2; ++k) {
        phi_grad(px, py, th, phi, gx, gy);
        g2 = gx * gx + gy * gy + T(1e-30);
        px = px - phi * gx / g2;
        py = py - phi * gy / g2;
      }
      phi_grad(px, py, th, phi, gx, gy);
      g2 = gx * gx + gy * gy + T(1e-30);
    }
    const T g = sqrt(g2);
    // signed distance along the normal at the projected point (− φ/|∇φ|: residual of the
    // projection), with the sign of φ(x), which is exact: far from a slender feature three
    // projections may not reach the surface and the normal there may point the wrong way
    using std::abs;
    const T Dn = ((x0 - px) * gx + (y0 - py) * gy) / g - phi / g;
    const T Dr = value(D0) >= 0 ? abs(Dn) : -abs(Dn);
    // C² blend from the refined distance (|D₀| ≤ refine_within/2) to D₀ (|D₀| ≥ refine_within),
    // so that μ(p) has no jump where a point crosses the refinement radius
    const double r1 = 0.5 * refine_within;
    if (ad <= r1) {
      D = Dr;
    } else {
      using std::abs;
      const T z = (T(refine_within) - abs(D0)) / T(refine_within - r1);  // 1 → 0
      const T w = z * z * z * (z * (T(6.0) * z - T(15.0)) + T(10.0));    // C² (quintic) smoothstep
      D = w * Dr + (T(1.0) - w) * D0;
    }
  }
  return hole_ ? D : -D;
}

template double Feature::distance<double>(const Vec2&, const double*, double, int) const;
template Dual Feature::distance<Dual>(const Vec2&, const Dual*, double, int) const;
template void Feature::phi_grad<double>(const double&, const double&, const double*, double&,
                                        double&, double&) const;
template void Feature::phi_grad<Dual>(const Dual&, const Dual&, const Dual*, Dual&, Dual&,
                                      Dual&) const;

double Feature::phi(const Vec2& x, const std::vector<double>& th) const {
  // sign and zero set of φ equal those of the normalized distance
  return distance<double>(x, th.data());
}

}  // namespace lsmbs
