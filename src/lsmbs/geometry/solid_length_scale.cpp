#include "lsmbs/geometry/solid_length_scale.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/solid_cell.hpp"
#include "lsmbs/geometry/length_scale_parts.hpp"

namespace lsmbs {
namespace {

using namespace length_scale_parts;
constexpr double kInf = std::numeric_limits<double>::infinity();

size_t profile_size(Feature::Type t) { return Feature::parameter_names(t).size(); }

template <class T>
T larger(const T& a, const T& b) {
  return value(a) > value(b) ? a : b;
}

// The exact distance to the product of two sets from the distances d1, d2 to each (> 0 outside):
// √(d1² + d2²) where both are outside, else the larger.
template <class T>
T product_distance(const T& d1, const T& d2) {
  if (value(d1) > 0 && value(d2) > 0) return sqrt(d1 * d1 + d2 * d2);
  return larger(d1, d2);
}

// g = (Σ |u_i/a_i|^ξ)^(1/ξ), u = Aᵀ(y − c): the super-ellipsoid's gauge (1 on its surface).
template <class T>
T gauge(const Feature3& f, const Vec3& y, const T* th) {
  const Mat3& A = f.frame().axes;
  const T dx = T(y.x()) - th[0], dy = T(y.y()) - th[1], dz = T(y.z()) - th[2];
  T S(0.0);
  for (int i = 0; i < 3; ++i)
    S = S + pow(abs(dx * A(0, i) + dy * A(1, i) + dz * A(2, i)) / th[3 + i], th[6]);
  return pow(S, T(1.0) / th[6]);
}

// The closest point of the surface Σ (y_i/a_i)^ξ = 1 (first octant) to q ≥ 0 outside it. Its
// conditions q_i = y_i + λ ξ y_i^(ξ−1)/a_i^ξ (λ ≥ 0) give each y_i(λ) as the root of a convex,
// increasing function of y_i (ξ ≥ 2), found by Newton's method; F(λ) = Σ (y_i(λ)/a_i)^ξ − 1
// falls monotonically with λ, and its root is found by Newton's method on λ (dF/dλ by implicit
// differentiation) kept within a bracket that bisection shrinks when a step leaves it.
Vec3 closest_on_super_ellipsoid(const Vec3& q, const Vec3& a, double xi) {
  Vec3 ax;
  for (int i = 0; i < 3; ++i) ax[i] = std::pow(a[i], xi);
  Vec3 y = q;  // warm start across λ (Newton on a convex increasing function converges from
               // either side after one step)
  double dF = 0;
  auto F = [&](double lambda) {
    double S = 0;
    dF = 0;
    for (int i = 0; i < 3; ++i) {
      const double k = lambda * xi / ax[i];
      double v = std::min(y[i], q[i]);
      for (int it = 0; it < 60 && q[i] > 0; ++it) {
        const double p = std::pow(v, xi - 2);
        const double step = (v + k * p * v - q[i]) / (1 + k * (xi - 1) * p);
        v = std::max(0.0, v - step);
        if (std::abs(step) <= 1e-14 * q[i]) break;
      }
      y[i] = q[i] > 0 ? v : 0;
      const double p = std::pow(y[i], xi - 2), g = xi * p * y[i] / ax[i];  // ∂F/∂y_i · (1/1)
      S += p * y[i] * y[i] / ax[i];
      dF -= g * (xi * p * y[i] / ax[i]) / (1 + k * (xi - 1) * p);  // ∂F/∂y_i · ∂y_i/∂λ
    }
    return S - 1;
  };
  double lo = 0, hi = INFINITY, lambda = 0;
  double f = F(lambda);
  for (int it = 0; it < 200 && std::abs(f) > 1e-14; ++it) {
    (f > 0 ? lo : hi) = lambda;
    double next = dF < 0 ? lambda - f / dF : INFINITY;
    if (!(next > lo && next < hi)) next = std::isfinite(hi) ? 0.5 * (lo + hi) : 4 * lo + 1e-300;
    if (next == lambda) break;
    lambda = next;
    f = F(lambda);
  }
  return y;
}

// A super-ellipsoid's signed distance: outside, exact (the closest point above; its derivatives
// by the envelope theorem, ∂s/∂θ = (∂g/∂θ)(y*)/|∇_y g(y*)|); inside, the lower bound on the depth
// (g − 1)·min(a, b, c) (g is 1/min(a, b, c)-Lipschitz), which the ligaments never take as their
// minimum (the sum of two distances is least outside both shapes).
template <class T>
T super_ellipsoid_distance(const Feature3& f, const Vec3& x, const T* th) {
  const T g = gauge(f, x, th);
  if (!(value(g) > 1)) {
    int k = 3;
    for (int i = 4; i < 6; ++i)
      if (value(th[i]) < value(th[k])) k = i;
    return (g - 1.0) * th[k];
  }
  const Mat3& A = f.frame().axes;
  const Vec3 c(value(th[0]), value(th[1]), value(th[2]));
  const Vec3 u = A.transpose() * (x - c);
  const Vec3 a(value(th[3]), value(th[4]), value(th[5]));
  const double xi = value(th[6]);
  Vec3 y = closest_on_super_ellipsoid(u.cwiseAbs(), a, xi);
  for (int i = 0; i < 3; ++i) y[i] = std::copysign(y[i], u[i]);
  const double dist = (u - y).norm();
  const Vec3 yw = c + A * y;  // the closest point in the body's coordinates
  // |∇_y g| at y*: ∂g/∂u_i = sign(u_i) (|u_i|/a_i)^(ξ−1) / (a_i g^(ξ−1)), g = 1 there
  double n2 = 0;
  for (int i = 0; i < 3; ++i) n2 += std::pow(std::pow(std::abs(y[i]) / a[i], xi - 1) / a[i], 2);
  const T gy = gauge(f, yw, th);
  return T(dist) + (gy - T(value(gy))) / std::sqrt(n2);
}

// s(x): the signed distance from x to feature f's shape, > 0 outside it (hole or solid), with
// T = Dual over its parameters θ. `profile`, `arc`: a pocket's or through-hole's planar shape.
template <class T>
T shape_distance3(const Feature3& f, const Feature* profile, const QuarterArc* arc, const Vec3& x,
                  const T* th) {
  switch (f.type()) {
    case Feature3::Type::kSphere:
      return f.distance<T>(x, th, 0);
    case Feature3::Type::kSuperEllipsoid:
      return super_ellipsoid_distance(f, x, th);
    case Feature3::Type::kCylinder: {
      const Vec3 a = f.frame().axes.col(2);
      const T dx = T(x.x()) - th[0], dy = T(x.y()) - th[1], dz = T(x.z()) - th[2];
      const T s = dx * a.x() + dy * a.y() + dz * a.z();
      const T rx = dx - s * a.x(), ry = dy - s * a.y(), rz = dz - s * a.z();
      const T dr = sqrt(rx * rx + ry * ry + rz * rz) - th[3];
      if (!(value(th[4]) > 0)) return dr;
      return product_distance(dr, T(abs(s) - th[4] * 0.5));
    }
    case Feature3::Type::kPocket:
    case Feature3::Type::kThroughHole: {
      const Vec3 uvw = f.frame().axes.transpose() * (x - f.frame().origin);
      const T d2 = shape_distance<T>(*profile, Vec2(uvw.x(), uvw.y()), th, arc);
      if (f.type() == Feature3::Type::kThroughHole) return d2;
      return product_distance(d2, T(uvw.z()) - th[profile_size(profile->type())]);
    }
  }
  return T(0.0);
}

// A lower bound on s(x) that costs less than s (to skip samples beyond the reach of every bound).
double distance_floor(const Feature3& f, const Feature* profile, const Vec3& x,
                      const std::vector<double>& th) {
  switch (f.type()) {
    case Feature3::Type::kSuperEllipsoid:  // and its first-order estimate, a bound outside
      return std::max((x - Vec3(th[0], th[1], th[2])).norm() - std::max({th[3], th[4], th[5]}),
                      f.distance<double>(x, th.data(), 0));
    case Feature3::Type::kPocket:
    case Feature3::Type::kThroughHole: {
      const Vec3 uvw = f.frame().axes.transpose() * (x - f.frame().origin);
      return (Vec2(uvw.x(), uvw.y()) - centre(*profile, th)).norm() - reach(*profile, th);
    }
    default:
      return -kInf;  // exact and cheap: evaluated
  }
}

// KS minimum of a few widths w_k = v_k (θ) of one feature, with ∂w_k/∂θ_{m_k} = dv_k.
struct Width {
  double v;
  int param;
  double dv;
};
LengthScaleConstraint member_of(const Feature3& f, const std::vector<Width>& widths, double delta,
                                double tolerance, int nv) {
  LengthScaleConstraint c;
  c.kind = "member", c.first = f.name(), c.bound = delta;
  c.gradient = Vec::Zero(nv);
  std::vector<double> v, w;
  for (const Width& x : widths) v.push_back(x.v);
  if (v.size() == 1) {
    c.value = v[0], w = {1.0};
  } else {
    c.value = ks_min(v, std::log(static_cast<double>(v.size())) / (tolerance * delta), w);
    c.error_bound = tolerance * delta;
  }
  for (size_t k = 0; k < widths.size(); ++k) {
    const ParamBinding& b = f.params()[static_cast<size_t>(widths[k].param)];
    if (b.variable >= 0) c.gradient[b.variable] += w[k] * widths[k].dv * b.scale;
  }
  return c;
}

}  // namespace

SolidLengthScale::SolidLengthScale(const SolidMesh& mesh, const LevelSet3& ls, int num_design,
                                   LengthScaleOptions o)
    : ls_(&ls), nd_(num_design), o_(o) {
  void_ = void_features(ls.root(), ls.features());
  if (auto msg = o.validate(); !msg.empty()) throw Error("length scale: " + msg);
  if (o.no_cut > 0)
    throw Error(
        "length scale: no_cut is planar only; on a solid body bound the distance to the faces "
        "with min_edge");
  if (mesh.num_elements() == 0) throw Error("length scale: the solid body's mesh has no cells");
  spacing_ = o.spacing > 0 ? o.spacing : median_longest_edge(mesh) / 4;
  // the faces that no other cell shares: the body's boundary
  std::map<std::vector<int>, int> count;
  auto key = [&](int e, const auto& corners) {
    std::vector<int> k;
    for (int c : corners) k.push_back(mesh.cells[static_cast<size_t>(e)][static_cast<size_t>(c)]);
    std::sort(k.begin(), k.end());
    return k;
  };
  auto for_faces = [&](int e, const auto& fn) {
    if (mesh.cells[static_cast<size_t>(e)].size() == 8)
      for (size_t f = 0; f < kHexFaces.size(); ++f) fn(f, key(e, kHexFaces[f].corners));
    else
      for (size_t f = 0; f < kTetFaces.size(); ++f) fn(f, key(e, kTetFaces[f]));
  };
  for (int e = 0; e < mesh.num_elements(); ++e)
    for_faces(e, [&](size_t, const std::vector<int>& k) { ++count[k]; });
  for (int e = 0; e < mesh.num_elements(); ++e) {
    std::vector<char> open(mesh.cells[static_cast<size_t>(e)].size() == 8 ? 6 : 4, 0);
    for_faces(e, [&](size_t f, const std::vector<int>& k) { open[f] = count[k] == 1; });
    if (open.size() == 6)
      sample_hexahedron(mesh, e, open);
    else
      sample_tetrahedron(mesh, e, open);
  }
  // the boundary samples' groups of normals (faces, for face_distances)
  std::vector<Vec3> group_normal;
  for (const Sample& b : boundary_) {
    size_t g = 0;
    while (g < group_normal.size() && b.n.dot(group_normal[g]) < std::sqrt(0.5)) ++g;
    if (g == group_normal.size()) group_normal.push_back(b.n);
    face_group_.push_back(static_cast<int>(g));
  }
  // each feature's planar profile
  for (const Feature3& f : ls.features()) {
    const bool profiled =
        f.type() == Feature3::Type::kPocket || f.type() == Feature3::Type::kThroughHole;
    profile_.push_back(profiled ? std::optional<Feature>(Feature(f.name(), f.profile(), {}, true))
                                : std::nullopt);
  }
}

void SolidLengthScale::sample_hexahedron(const SolidMesh& mesh, int e,
                                         const std::vector<char>& open_face) {
  const auto& cell = mesh.cells[static_cast<size_t>(e)];
  std::array<int, 3> n{};  // sub-cells per parent axis: its longest edge over the spacing
  for (int a = 0; a < 3; ++a) {
    double len = 0;
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 8; ++j) {
        int differ = 0;
        for (int k = 0; k < 3; ++k) differ += kHexCorner[i][k] != kHexCorner[j][k];
        if (differ == 1 && kHexCorner[i][a] != kHexCorner[j][a])
          len = std::max(len, (mesh.nodes[static_cast<size_t>(cell[static_cast<size_t>(i)])] -
                               mesh.nodes[static_cast<size_t>(cell[static_cast<size_t>(j)])])
                                  .norm());
      }
    n[static_cast<size_t>(a)] = std::max(1, static_cast<int>(std::ceil(len / spacing_ - 1e-9)));
  }
  auto mid = [&](int a, int i) { return -1 + (2.0 * i + 1) / n[static_cast<size_t>(a)]; };
  double detJ = 0;
  const double w0 = 8.0 / (n[0] * n[1] * n[2]);  // the sub-cell's parent volume
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const Vec3 x = hex_point(mesh, e, Vec3(mid(0, i), mid(1, j), mid(2, k)), detJ);
        volume_.push_back({x, Vec3::Zero(), detJ * w0});
      }
  const Vec3 centre = hex_point(mesh, e, Vec3::Zero(), detJ);
  for (size_t f = 0; f < kHexFaces.size(); ++f) {
    if (!open_face[f]) continue;
    const int a = kHexFaces[f].axis, b = (a + 1) % 3, c = (a + 2) % 3;
    // the lattice of the face's sub-cells, its edges and corners included (a minimum on an edge
    // of the body is sampled where it lies)
    auto node = [&](int ax, int i) { return -1 + 2.0 * i / n[static_cast<size_t>(ax)]; };
    for (int j = 0; j <= n[static_cast<size_t>(c)]; ++j)
      for (int i = 0; i <= n[static_cast<size_t>(b)]; ++i) {
        Vec3 s;
        s[a] = kHexFaces[f].side, s[b] = node(b, i), s[c] = node(c, j);
        const Vec3 x = hex_point(mesh, e, s, detJ);
        Vec3 sb = s, sc = s;  // the face's tangents by differences of the map
        sb[b] += 1e-3, sc[c] += 1e-3;
        Vec3 nrm = (hex_point(mesh, e, sb, detJ) - x).cross(hex_point(mesh, e, sc, detJ) - x);
        if (nrm.dot(x - centre) < 0) nrm = -nrm;
        boundary_.push_back({x, nrm.normalized()});
      }
  }
}

void SolidLengthScale::sample_tetrahedron(const SolidMesh& mesh, int e,
                                          const std::vector<char>& open_face) {
  const auto& cell = mesh.cells[static_cast<size_t>(e)];
  auto X = [&](int k) -> const Vec3& {
    return mesh.nodes[static_cast<size_t>(cell[static_cast<size_t>(k)])];
  };
  const int n = std::max(1, static_cast<int>(std::ceil(longest_edge(mesh, e) / spacing_ - 1e-9)));
  // the centroids of the lattice's upright sub-tetrahedra, sharing the cell's volume
  const size_t first = volume_.size();
  for (int i = 0; i < n; ++i)
    for (int j = 0; i + j < n; ++j)
      for (int k = 0; i + j + k < n; ++k)
        volume_.push_back({X(0) + ((i + 0.25) * (X(1) - X(0)) + (j + 0.25) * (X(2) - X(0)) +
                                   (k + 0.25) * (X(3) - X(0))) /
                                      n});
  Mat3 J;
  for (int k = 0; k < 3; ++k) J.col(k) = X(k + 1) - X(0);
  const double share = std::abs(J.determinant()) / 6 / static_cast<double>(volume_.size() - first);
  for (size_t k = first; k < volume_.size(); ++k) volume_[k].w = share;
  for (size_t f = 0; f < kTetFaces.size(); ++f) {
    if (!open_face[f]) continue;
    const Vec3 &A = X(kTetFaces[f][0]), &B = X(kTetFaces[f][1]), &C = X(kTetFaces[f][2]);
    Vec3 nrm = (B - A).cross(C - A);
    if (nrm.dot(A - X(static_cast<int>(f))) < 0) nrm = -nrm;  // away from the opposite corner
    nrm.normalize();
    for (int i = 0; i <= n; ++i)  // the face's lattice, its edges and corners included
      for (int j = 0; i + j <= n; ++j)
        boundary_.push_back({A + (i * (B - A) + j * (C - A)) / n, nrm});
  }
}

std::vector<char> SolidLengthScale::edge_samples(int i, const std::vector<double>& th) const {
  const Feature3& f = ls_->features()[static_cast<size_t>(i)];
  const bool cylinder = f.type() == Feature3::Type::kCylinder;
  const bool through = f.type() == Feature3::Type::kThroughHole || (cylinder && !(th[4] > 0));
  const bool pocket = f.type() == Feature3::Type::kPocket;
  if (!through && !pocket) return {};
  const Mat3& A = f.frame().axes;
  const Vec3 a = A.col(2);
  const Vec3 c =
      cylinder ? Vec3(th[0], th[1], th[2]) : Vec3(f.frame().origin + A * Vec3(th[0], th[1], 0));
  // where the axis line leaves the body: the samples nearest it among those facing +a and among
  // those facing −a (a pocket: facing −a, its entry, short of half its depth)
  const double half_depth = pocket ? 0.5 * th[profile_size(f.profile())] : 0;
  double best[2] = {INFINITY, INFINITY};
  int anchor[2] = {-1, -1};
  for (size_t k = 0; k < boundary_.size(); ++k) {
    const double na = boundary_[k].n.dot(a);
    if (std::abs(na) < 1e-6 || (pocket && na > 0)) continue;
    const Vec3 d = boundary_[k].x - c;
    const double t = d.dot(a), r = (d - t * a).norm();
    if (pocket && t >= half_depth) continue;
    const int side = na < 0 ? 0 : 1;
    if (r < best[side]) best[side] = r, anchor[side] = static_cast<int>(k);
  }
  std::vector<char> use(boundary_.size(), 1);
  for (const int k0 : anchor) {
    if (k0 < 0) continue;
    const Vec3& n0 = boundary_[static_cast<size_t>(k0)].n;
    for (size_t k = 0; k < boundary_.size(); ++k)
      if (boundary_[k].n.dot(n0) >= std::sqrt(0.5)) use[k] = 0;  // within 45° of the face's
  }
  return use;
}

std::vector<SolidLengthScale::FaceDistance> SolidLengthScale::face_distances(
    int i, const std::vector<std::vector<double>>& theta, double cap) const {
  const auto& th = theta[static_cast<size_t>(i)];
  const Feature3& f = ls_->features()[static_cast<size_t>(i)];
  const auto& p = profile_[static_cast<size_t>(i)];
  const QuarterArc arc = p ? arc_of(p->type(), th) : QuarterArc(0, 0, 1, 1);
  const std::vector<char> use = edge_samples(i, th);
  std::vector<FaceDistance> best;
  std::vector<char> found;
  for (size_t k = 0; k < boundary_.size(); ++k) {
    if (!use.empty() && !use[k]) continue;
    const size_t g = static_cast<size_t>(face_group_[k]);
    if (g >= best.size()) best.resize(g + 1), found.resize(g + 1, 0);
    const double bound = found[g] ? best[g].value : cap;
    if (distance_floor(f, p ? &*p : nullptr, boundary_[k].x, th) >= bound) continue;
    const double s = shape_distance3<double>(f, p ? &*p : nullptr, &arc, boundary_[k].x, th.data());
    if (s < bound) best[g] = {s, boundary_[k].x, boundary_[k].n}, found[g] = 1;
  }
  std::vector<FaceDistance> out;
  for (size_t g = 0; g < best.size(); ++g)
    if (found[g]) out.push_back(best[g]);
  return out;
}

double SolidLengthScale::shape_distance(int i, const Vec3& x,
                                        const std::vector<std::vector<double>>& theta) const {
  const auto& th = theta[static_cast<size_t>(i)];
  const auto& p = profile_[static_cast<size_t>(i)];
  const QuarterArc arc = p ? arc_of(p->type(), th) : QuarterArc(0, 0, 1, 1);
  return shape_distance3<double>(ls_->features()[static_cast<size_t>(i)], p ? &*p : nullptr, &arc,
                                 x, th.data());
}

std::vector<std::string> SolidLengthScale::all_names() const {
  return constraint_names(ls_->features(), void_, nd_, o_);  // no_cut: refused on solids
}

std::vector<LengthScaleConstraint> SolidLengthScale::evaluate_all(const Vec& p) const {
  const auto& F = ls_->features();
  const int nf = static_cast<int>(F.size());
  const auto theta = ls_->values(p);
  const double cap = 3 * std::max(o_.min_ligament, o_.min_edge);
  std::vector<QuarterArc> arcs;  // each profile's tabulated curve at p
  for (int i = 0; i < nf; ++i)
    arcs.push_back(
        profile_[static_cast<size_t>(i)]
            ? arc_of(profile_[static_cast<size_t>(i)]->type(), theta[static_cast<size_t>(i)])
            : QuarterArc(0, 0, 1, 1));
  auto feature = [&](int i) -> const Feature3& { return F[static_cast<size_t>(i)]; };
  auto profile = [&](int i) {
    return profile_[static_cast<size_t>(i)] ? &*profile_[static_cast<size_t>(i)] : nullptr;
  };
  // s_i at every sample within reach of a bound (+∞ beyond)
  auto distances = [&](const std::vector<Sample>& S) {
    std::vector<std::vector<double>> d(static_cast<size_t>(nf));
    for (int i = 0; i < nf; ++i) {
      const auto& th = theta[static_cast<size_t>(i)];
      auto& di = d[static_cast<size_t>(i)];
      di.assign(S.size(), kInf);
      for (size_t k = 0; k < S.size() && cap > 0; ++k)
        if (distance_floor(feature(i), profile(i), S[k].x, th) < cap)
          di[k] = shape_distance3<double>(feature(i), profile(i), &arcs[static_cast<size_t>(i)],
                                          S[k].x, th.data());
    }
    return d;
  };
  const std::vector<Sample> none;
  const auto dv = distances(o_.min_ligament > 0 ? volume_ : none);
  const auto db = distances(o_.min_edge > 0 ? boundary_ : none);
  auto gradient = [&](int i, const Vec3& x, double weight, Vec& grad) {
    const auto& th = theta[static_cast<size_t>(i)];
    std::array<Dual, kMaxFeatureParams> t;
    for (size_t m = 0; m < th.size(); ++m) t[m] = Dual::variable(th[m], static_cast<int>(m));
    const Dual s =
        shape_distance3<Dual>(feature(i), profile(i), &arcs[static_cast<size_t>(i)], x, t.data());
    for (size_t m = 0; m < th.size(); ++m) {
      const ParamBinding& b = feature(i).params()[m];
      if (b.variable >= 0) grad[b.variable] += weight * s.d[m] * b.scale;
    }
  };
  auto centre_of = [&](int i) -> Vec {
    const auto& th = theta[static_cast<size_t>(i)];
    if (!profile(i)) return Vec3(th[0], th[1], th[2]);
    const Vec2 c = centre(*profile(i), th);
    return Vec(feature(i).frame().origin + feature(i).frame().axes * Vec3(c.x(), c.y(), 0));
  };
  std::vector<LengthScaleConstraint> out;
  auto aggregate = [&](const std::string& kind, int i, int j, double delta,
                       const std::vector<Sample>& S, const std::vector<std::vector<double>>& d,
                       const std::vector<char>& use) {
    LengthScaleConstraint c;
    c.kind = kind, c.bound = delta, c.first = feature(i).name();
    if (j >= 0) c.second = feature(j).name();
    c.gradient = Vec::Zero(p.size());
    const double rho =
        std::log(static_cast<double>(std::max<size_t>(2, S.size()))) / (o_.tolerance * delta);
    c.error_bound = o_.tolerance * delta;
    const auto m = sampled_minimum(d[static_cast<size_t>(i)],
                                   j >= 0 ? &d[static_cast<size_t>(j)] : nullptr, use, cap, rho);
    if (!m.any) {  // nothing within reach: the bound holds with room, flat there
      c.value = cap, c.at = centre_of(i);
      out.push_back(std::move(c));
      return;
    }
    c.value = m.value, c.at = S[m.argmin].x;
    for (const auto& [k, w] : m.weights) {
      gradient(i, S[k].x, w, c.gradient);
      if (j >= 0) gradient(j, S[k].x, w, c.gradient);
    }
    if (c.value > cap) c.value = cap, c.gradient.setZero();
    out.push_back(std::move(c));
  };
  for (int i = 0; i < nd_; ++i) {
    if (!void_[static_cast<size_t>(i)]) continue;
    if (o_.min_ligament > 0)
      for (int j = i + 1; j < nf; ++j)
        if (j >= nd_ || void_[static_cast<size_t>(j)])
          aggregate("ligament", i, j, o_.min_ligament, volume_, dv, {});
    if (o_.min_edge > 0)
      aggregate("edge", i, -1, o_.min_edge, boundary_, db,
                edge_samples(i, theta[static_cast<size_t>(i)]));
  }
  if (o_.min_member > 0)
    for (int i = 0; i < nd_; ++i) {
      const Feature3& f = feature(i);
      const auto& th = theta[static_cast<size_t>(i)];
      const int nv = static_cast<int>(p.size());
      LengthScaleConstraint c;
      switch (f.type()) {
        case Feature3::Type::kSphere:
          c = member_of(f, {{2 * th[3], 3, 2}}, o_.min_member, o_.tolerance, nv);
          break;
        case Feature3::Type::kCylinder:
          c = th[4] > 0 ? member_of(f, {{2 * th[3], 3, 2}, {th[4], 4, 1}}, o_.min_member,
                                    o_.tolerance, nv)
                        : member_of(f, {{2 * th[3], 3, 2}}, o_.min_member, o_.tolerance, nv);
          break;
        case Feature3::Type::kSuperEllipsoid:
          c = member_of(f, {{2 * th[3], 3, 2}, {2 * th[4], 4, 2}, {2 * th[5], 5, 2}}, o_.min_member,
                        o_.tolerance, nv);
          break;
        case Feature3::Type::kPocket:
        case Feature3::Type::kThroughHole:
          c = member_size(f.name(), f.profile(), f.params(), th, o_.min_member, o_.tolerance, nv);
          break;
      }
      c.at = centre_of(i);
      out.push_back(std::move(c));
    }
  return out;
}

}  // namespace lsmbs
