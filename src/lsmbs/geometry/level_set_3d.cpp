#include "lsmbs/geometry/level_set_3d.hpp"

#include <algorithm>
#include <cmath>

namespace lsmbs {

namespace {

// The number of a profile's own parameters (a pocket's depth follows them).
size_t profile_size(Feature::Type t) { return Feature::parameter_names(t).size(); }

}  // namespace

Feature3::Feature3(std::string name, Type type, std::vector<ParamBinding> params, bool hole,
                   Frame3 frame, Feature::Type profile)
    : name_(std::move(name)),
      type_(type),
      params_(std::move(params)),
      hole_(hole),
      frame_(std::move(frame)),
      profile_(name_, profile, {}, true) {}

const std::vector<std::string>& Feature3::type_names() {
  static const std::vector<std::string> names = {"sphere", "cylinder", "super_ellipsoid", "pocket",
                                                 "through_hole"};
  return names;
}

Feature3::Type Feature3::parse_type(const std::string& s, bool* ok) {
  const auto& n = type_names();
  const auto it = std::find(n.begin(), n.end(), s);
  *ok = it != n.end();
  return *ok ? static_cast<Type>(it - n.begin()) : Type::kSphere;
}

std::vector<std::string> Feature3::parameter_names(Type t, Feature::Type profile) {
  switch (t) {
    case Type::kSphere:
      return {"cx", "cy", "cz", "r"};
    case Type::kCylinder:
      return {"cx", "cy", "cz", "r", "length"};
    case Type::kSuperEllipsoid:
      return {"cx", "cy", "cz", "a", "b", "c", "xi"};
    case Type::kPocket: {
      auto names = Feature::parameter_names(profile);
      names.push_back("depth");
      return names;
    }
    case Type::kThroughHole:
      return Feature::parameter_names(profile);
  }
  return {};
}

std::vector<double> Feature3::values(const Vec& p) const {
  std::vector<double> v;
  for (const auto& b : params_) v.push_back(b.value(p));
  return v;
}

std::string Feature3::check(const std::vector<double>& th) const {
  const auto positive = [&](size_t i, const char* what) -> std::string {
    return th[i] > 0 && std::isfinite(th[i]) ? "" : std::string(what) + " must be positive";
  };
  switch (type_) {
    case Type::kSphere:
      return positive(3, "the radius r");
    case Type::kCylinder:
      if (auto m = positive(3, "the radius r"); !m.empty()) return m;
      return th[4] >= 0 ? "" : "the length must be ≥ 0 (0: through the whole part)";
    case Type::kSuperEllipsoid:
      for (size_t i = 3; i < 6; ++i)
        if (auto m = positive(i, "the semi-axes a, b, c"); !m.empty()) return m;
      return th[6] >= 2 ? "" : "the exponent xi must be ≥ 2 (a convex, rounded box)";
    case Type::kPocket:
    case Type::kThroughHole: {
      const size_t n = profile_size(profile_.type());
      if (auto m = profile_.check(std::vector<double>(th.begin(), th.begin() + n)); !m.empty())
        return "profile: " + m;
      return type_ == Type::kPocket ? positive(n, "the depth") : "";
    }
  }
  return {};
}

template <class T>
T Feature3::distance(const Vec3& x, const T* th, double refine_within) const {
  const Vec3 d = x - frame_.origin;
  const Vec3 uvw = frame_.axes.transpose() * d;  // the point in the feature's frame
  switch (type_) {
    case Type::kSphere: {
      const T dx = T(x.x()) - th[0], dy = T(x.y()) - th[1], dz = T(x.z()) - th[2];
      return sqrt(dx * dx + dy * dy + dz * dz) - th[3];
    }
    case Type::kCylinder: {
      const Vec3 a = frame_.axes.col(2);
      const T dx = T(x.x()) - th[0], dy = T(x.y()) - th[1], dz = T(x.z()) - th[2];
      const T s = dx * a.x() + dy * a.y() + dz * a.z();
      const T rx = dx - s * a.x(), ry = dy - s * a.y(), rz = dz - s * a.z();
      const T Dr = sqrt(rx * rx + ry * ry + rz * rz) - th[3];
      if (!(value(th[4]) > 0)) return Dr;
      const T Dl = abs(s) - th[4] * 0.5;  // the caps
      return value(Dl) > value(Dr) ? Dl : Dr;
    }
    case Type::kSuperEllipsoid: {
      const Mat3& A = frame_.axes;
      const T dx = T(x.x()) - th[0], dy = T(x.y()) - th[1], dz = T(x.z()) - th[2];
      const T xi = th[6];
      T S(0.0), grad2(0.0), s[3];
      for (int i = 0; i < 3; ++i) {
        const T u = dx * A(0, i) + dy * A(1, i) + dz * A(2, i);
        s[i] = abs(u) / th[3 + i];
        S = S + pow(s[i], xi);
      }
      const double amin = std::min({value(th[3]), value(th[4]), value(th[5])});
      if (!(value(S) > 1e-30)) {  // the centre: ∇g = 0; the nearest vertex is min(a, b, c) away
        for (int i = 3; i < 6; ++i)
          if (value(th[i]) == amin) return -th[i];
      }
      const T g = pow(S, T(1.0) / xi);
      // ∂g/∂u_i = sign(u_i) s_i^(ξ−1) / (a_i g^(ξ−1)); |∇_x g| = |∇_u g| (orthonormal frame)
      const T gp = pow(g, xi - 1.0);
      for (int i = 0; i < 3; ++i) {
        const T gi = pow(s[i], xi - 1.0) / (th[3 + i] * gp);
        grad2 = grad2 + gi * gi;
      }
      return (g - 1.0) / sqrt(grad2);
    }
    case Type::kPocket:
    case Type::kThroughHole: {
      const T D2 = profile_.distance<T>(Vec2(uvw.x(), uvw.y()), th, refine_within);
      if (type_ == Type::kThroughHole) return D2;
      const T Dw = T(uvw.z()) - th[profile_size(profile_.type())];  // below the pocket's floor
      return value(Dw) > value(D2) ? Dw : D2;
    }
  }
  return T(0.0);
}

template double Feature3::distance<double>(const Vec3&, const double*, double) const;
template Dual Feature3::distance<Dual>(const Vec3&, const Dual*, double) const;

double Feature3::bound(const Vec3& x, const double* th, double refine_within, double rho) const {
  if ((type_ == Type::kPocket || type_ == Type::kThroughHole) &&
      !profile_.exact_distance(std::vector<double>(th, th + profile_size(profile_.type())))) {
    const Vec3 uvw = frame_.axes.transpose() * (x - frame_.origin);
    const double L = profile_.far_bound(
        Vec2(uvw.x(), uvw.y()), rho, std::vector<double>(th, th + profile_size(profile_.type())));
    const double B2 =
        L != 0 && std::abs(L) >= refine_within ? std::copysign(std::abs(L) + rho, L) : 0.0;
    if (type_ == Type::kThroughHole) return B2;
    return std::max(B2, uvw.z() - th[profile_size(profile_.type())]);  // the floor: exact
  }
  const double D = distance<double>(x, th, refine_within);
  if (type_ != Type::kSuperEllipsoid || D >= 0) return D;
  // inside a super-ellipsoid: (1 − g)·min(a, b, c) ≤ the distance to its surface
  const Vec3 u = frame_.axes.transpose() * (x - Vec3(th[0], th[1], th[2]));
  double S = 0;
  for (int i = 0; i < 3; ++i) S += std::pow(std::abs(u[i]) / th[3 + i], th[6]);
  const double g = std::pow(S, 1 / th[6]);
  return std::min(0.0, g - 1) * std::min({th[3], th[4], th[5]});
}

LevelSet3::LevelSet3(std::vector<Feature3> features, LevelSetNode root, int nv)
    : features_(std::move(features)), root_(std::move(root)), nv_(nv) {
  const auto slack = [](const LevelSetNode& n, const auto& self) -> double {
    double s = 0;
    for (const auto& c : n.children) s = std::max(s, self(c, self));
    if (n.ks > 0) s += std::log(static_cast<double>(n.children.size())) / n.ks;
    return s;
  };
  slack_ = slack(root_, slack);
}

std::vector<std::vector<double>> LevelSet3::values(const Vec& p) const {
  std::vector<std::vector<double>> v;
  for (const auto& f : features_) v.push_back(f.values(p));
  return v;
}

double LevelSet3::feature_distance(int fi, const Vec3& x,
                                   const std::vector<std::vector<double>>& theta,
                                   Gradient* grad) const {
  const Feature3& f = features_[static_cast<size_t>(fi)];
  const auto& th = theta[static_cast<size_t>(fi)];
  const double sign = f.hole() ? 1.0 : -1.0;
  if (!grad) return sign * f.distance<double>(x, th.data(), refine_within_);
  Dual t[kMaxFeatureParams];
  for (size_t i = 0; i < th.size(); ++i) t[i] = Dual::variable(th[i], static_cast<int>(i));
  const Dual D = f.distance<Dual>(x, t, refine_within_);
  for (size_t i = 0; i < th.size(); ++i) {
    const auto& b = f.params()[i];
    if (b.variable >= 0) grad->emplace_back(b.variable, sign * D.d[i] * b.scale);
  }
  return sign * D.v;
}

double LevelSet3::evaluate(const Vec3& x, const std::vector<std::vector<double>>& theta,
                           Gradient* grad) const {
  if (grad) grad->clear();
  const auto leaf = [&](int f, Gradient* g) { return feature_distance(f, x, theta, g); };
  return evaluate_csg(root_, leaf, grad, nv_);
}

bool LevelSet3::tie_at(const Vec3& x, const std::vector<std::vector<double>>& theta,
                       double tol) const {
  Gradient grad;
  bool tie = false;
  const auto leaf = [&](int f, Gradient* g) { return feature_distance(f, x, theta, g); };
  evaluate_csg(root_, leaf, &grad, nv_, &tol, &tie);
  return tie;
}

double LevelSet3::bound(const Vec3& x, const std::vector<std::vector<double>>& theta,
                        double rho) const {
  const auto leaf = [&](int f, Gradient*) {
    const Feature3& F = features_[static_cast<size_t>(f)];
    const double b = F.bound(x, theta[static_cast<size_t>(f)].data(), refine_within_, rho);
    return F.hole() ? b : -b;
  };
  return evaluate_csg(root_, leaf, nullptr, nv_);
}

}  // namespace lsmbs
