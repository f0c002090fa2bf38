#include "lsmbs/design/design.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "lsmbs/core/error.hpp"
#include "lsmbs/mbs/model_builder.hpp"

namespace lsmbs {

Vec Design::initial() const {
  Vec v(size());
  for (int i = 0; i < size(); ++i) v[i] = variables[i].initial;
  return v;
}
double Design::snap_to_bounds(int i, double v) const {
  const auto& x = variables[static_cast<size_t>(i)];
  const double tol = kBoundTolerance * (x.upper - x.lower);
  if (std::abs(v - x.lower) <= tol) return x.lower;
  if (std::abs(v - x.upper) <= tol) return x.upper;
  return v;
}

Vec Design::lower() const {
  Vec v(size());
  for (int i = 0; i < size(); ++i) v[i] = variables[i].lower;
  return v;
}
Vec Design::upper() const {
  Vec v(size());
  for (int i = 0; i < size(); ++i) v[i] = variables[i].upper;
  return v;
}

int Design::add_variable(const std::string& name, double initial, double lower, double upper) {
  // the field at fault is the error's: name, upper or initial
  if (variable_index(name) >= 0)
    throw SetupError("design.variables", "duplicate design variable '" + name + "'", name, "name");
  if (!(upper > lower))
    throw SetupError("design.variables", "expected upper > lower", name, "upper");
  // within round-off of a bound (kBoundTolerance of the range): that bound
  const double tol = kBoundTolerance * (upper - lower);
  if (std::abs(initial - lower) <= tol) initial = lower;
  if (std::abs(initial - upper) <= tol) initial = upper;
  if (!(initial >= lower && initial <= upper)) {
    char b[160];
    std::snprintf(b, sizeof b, "initial value %.17g is outside its bounds [%.17g, %.17g]", initial,
                  lower, upper);
    throw SetupError("design.variables", b, name, "initial");
  }
  variables.push_back({name, initial, lower, upper});
  return size() - 1;
}

ParamBinding Design::variable(const std::string& name, double scale, double offset) const {
  const int k = variable_index(name);
  if (k < 0) throw SetupError("design.variables", "unknown design variable '" + name + "'");
  return ParamBinding{offset, scale, k};
}

void Design::add_geometry(const FlexibleBody& body, std::vector<Feature> features,
                          MappingOptions o) {
  for (const auto& b : bodies)
    if (b.body == &body)
      throw SetupError("design.geometry", "body '" + body.name + "' has two geometries");
  LevelSetNode root = LevelSetNode::all_of(static_cast<int>(features.size()));
  BodyDesign bd;
  bd.body = &body;
  bd.num_design_features = static_cast<int>(features.size());
  bd.map = std::make_unique<DesignMap>(body.mesh,
                                       LevelSet(std::move(features), std::move(root), size()), o);
  bodies.push_back(std::move(bd));
}

void Design::bind(int parameter, const std::string& variable, double scale, double offset,
                  const std::string& name) {
  const int k = variable_index(variable);
  if (k < 0) throw SetupError("design.parameters", "unknown design variable '" + variable + "'");
  if (parameter < 0)
    throw SetupError("design.parameters",
                     "unknown model parameter (index " + std::to_string(parameter) + ")");
  const std::string shown = name.empty() ? "#" + std::to_string(parameter) : name;
  for (const auto& o : bindings)
    if (o.parameter == parameter)
      throw SetupError("design.parameters", "parameter '" + shown + "' is bound twice", "",
                       "parameter");
  // the parameter stays admissible over the variable's bounds (it is affine in it)
  const DesignVariable& dv = variables[static_cast<size_t>(k)];
  if (!name.empty())
    for (const double x : {dv.lower, dv.upper}) {
      const double value = offset + scale * x;
      if (auto msg = ModelBuilder::check_parameter_value(name, value); !msg.empty()) {
        char b[200];
        std::snprintf(b, sizeof b,
                      "parameter '%s' = %g at %s = %g (a bound of the variable): ", name.c_str(),
                      value, variable.c_str(), x);
        throw SetupError("design.parameters", b + msg);
      }
    }
  bindings.push_back({parameter, k, offset, scale});
}

namespace {

// The region of the design features [0, nd) (their intersection by default, eq. 4), OR-ed with
// every non-design feature [nd, n) (§2.2: material kept there whatever the design does).
LevelSetNode region_with_non_design(const std::optional<LevelSetNode>& region, int nd, int n) {
  LevelSetNode root = region ? *region : LevelSetNode::all_of(nd);
  if (n == nd) return root;
  LevelSetNode any;
  any.op = LevelSetNode::Op::kOr;
  if (!root.children.empty() || root.op == LevelSetNode::Op::kFeature)
    any.children.push_back(std::move(root));
  for (int i = nd; i < n; ++i) {
    LevelSetNode leaf;
    leaf.feature = i;
    any.children.push_back(leaf);
  }
  return any;
}

// A parameter list's least and largest values over the design bounds (each parameter is affine
// in one variable: its extremes are at the variable's bounds).
void binding_range(const Design& d, const std::vector<ParamBinding>& params,
                   std::vector<double>& lo, std::vector<double>& hi) {
  lo.clear(), hi.clear();
  for (const auto& b : params) {
    const double a = b.variable < 0 ? b.offset : b.offset + b.scale * d.variables[b.variable].lower;
    const double c = b.variable < 0 ? b.offset : b.offset + b.scale * d.variables[b.variable].upper;
    lo.push_back(std::min(a, c));
    hi.push_back(std::max(a, c));
  }
}

// Distance between two axis-aligned boxes [a0, a1] and [b0, b1] (0 where they overlap).
template <int N>
double box_gap(const Eigen::Matrix<double, N, 1>& a0, const Eigen::Matrix<double, N, 1>& a1,
               const Eigen::Matrix<double, N, 1>& b0, const Eigen::Matrix<double, N, 1>& b1) {
  return (a0 - b1).cwiseMax(b0 - a1).cwiseMax(0.0).norm();
}

// Whether some parameter values within [lo, hi] could bring a 3D feature onto an element of the
// mesh (conservative: the elements' bounding boxes, and a shape inside a simple hull). A sphere,
// capped cylinder or super-ellipsoid (ξ ≥ 2: inside the box |u| ≤ a, |v| ≤ b, |w| ≤ c) lies in a
// ball about its centre of radius r, √(r² + L²/4) or |(a, b, c)|; a through-cylinder, a pocket
// or a through-hole in a cylinder of radius R about a line along the frame's w through the
// centre (R: r, or the planar profile's reach d·max(a, b) or |(a, b)|). The centre ranges over
// the box of its bounds; its image under the frame's Aᵀ over the box's interval image.
bool solid_feature_can_reach(const Feature3& f, const std::vector<double>& lo,
                             const std::vector<double>& hi, const SolidMesh& mesh) {
  using T = Feature3::Type;
  const Mat3& A = f.frame().axes;
  bool line = f.type() == T::kPocket || f.type() == T::kThroughHole;
  double R = 0;
  Vec3 c0 = Vec3::Zero(), c1 = Vec3::Zero();  // the centre's box (body frame, or (u, v) on a line)
  if (line) {
    const Feature::Type p = f.profile();
    R = p == Feature::Type::kCircle    ? hi[2]
        : p == Feature::Type::kEllipse ? hi[4] * std::max(hi[2], hi[3])
                                       : std::hypot(hi[2], hi[3]);
    const Vec3 o = A.transpose() * f.frame().origin;  // x = o + A(u, v, w): Aᵀx = Aᵀo + (u, v, w)
    c0 << o[0] + lo[0], o[1] + lo[1], 0;
    c1 << o[0] + hi[0], o[1] + hi[1], 0;
  } else {
    c0 << lo[0], lo[1], lo[2];
    c1 << hi[0], hi[1], hi[2];
    if (f.type() == T::kSphere)
      R = hi[3];
    else if (f.type() == T::kSuperEllipsoid)
      R = Vec3(hi[3], hi[4], hi[5]).norm();
    else if (lo[4] > 0)  // a capped cylinder
      R = std::hypot(hi[3], hi[4] / 2);
    else {  // a cylinder through everything: a line along its axis
      R = hi[3];
      line = true;
      Vec3 a = Vec3::Zero(), b = Vec3::Zero();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          a[i] += std::min(A(j, i) * c0[j], A(j, i) * c1[j]),
              b[i] += std::max(A(j, i) * c0[j], A(j, i) * c1[j]);
      c0 = a, c1 = b;
      c0[2] = c1[2] = 0;
    }
  }
  for (const auto& cell : mesh.cells) {
    Vec3 e0 = Vec3::Constant(std::numeric_limits<double>::infinity()), e1 = -e0;
    for (int n : cell) {
      const Vec3& x = mesh.nodes[static_cast<size_t>(n)];
      const Vec3 y = line ? Vec3(A.col(0).dot(x), A.col(1).dot(x), 0) : x;
      e0 = e0.cwiseMin(y), e1 = e1.cwiseMax(y);
    }
    if (box_gap<3>(e0, e1, c0, c1) <= R) return true;
  }
  return false;
}

}  // namespace

void Design::add_geometry(const SolidBody& body, SolidGeometrySpec spec) {
  for (const auto& b : solid_bodies)
    if (b.body == &body)
      throw SetupError("design.geometry", "body '" + body.name + "' has two geometries");
  const int nd = static_cast<int>(spec.features.size());
  std::vector<Feature3> feats = std::move(spec.features);
  for (auto& f : spec.non_design) feats.push_back(std::move(f));
  std::vector<double> lo, hi;
  for (const Feature3& f : feats) {
    binding_range(*this, f.params(), lo, hi);
    for (const auto* th : {&lo, &hi})
      if (auto msg = f.check(*th); !msg.empty())
        throw SetupError(
            "design.geometry",
            "feature '" + f.name() + "' is degenerate within the design bounds: " + msg, f.name());
  }
  LevelSetNode root = region_with_non_design(spec.region, nd, static_cast<int>(feats.size()));
  SolidBodyDesign bd;
  bd.body = &body;
  bd.num_design_features = nd;
  bd.map = std::make_unique<SolidDesignMap>(
      body.mesh, LevelSet3(std::move(feats), std::move(root), size()), spec.options);
  // as for planar bodies (below): a feature wholly outside is refused when no variable moves it,
  // or when no values within the bounds can bring it onto an element
  for (int k : bd.map->features_outside_mesh(initial())) {
    const Feature3& f = bd.map->level_set().features()[static_cast<size_t>(k)];
    bool moved = false;
    for (const auto& b : f.params()) moved = moved || (b.variable >= 0 && b.scale != 0);
    binding_range(*this, f.params(), lo, hi);
    if (moved && solid_feature_can_reach(f, lo, hi, body.mesh)) continue;
    throw SetupError("design.geometry",
                     std::string(k >= nd ? "non-design feature '" : "feature '") + f.name() +
                         "' lies wholly outside body '" + body.name +
                         "' (it overlaps no element), and " +
                         (moved ? "no values of its design variables within their bounds bring "
                                  "it in"
                                : "no design variable moves it") +
                         ": it has no effect; check its centre, size and frame against the mesh",
                     f.name());
  }
  solid_bodies.push_back(std::move(bd));
}

void Design::add_geometry(const FlexibleBody& body, GeometrySpec spec) {
  for (const auto& b : bodies)
    if (b.body == &body)
      throw SetupError("design.geometry", "body '" + body.name + "' has two geometries");
  const int nd = static_cast<int>(spec.features.size());
  std::vector<Feature> feats = std::move(spec.features);
  for (auto& f : spec.non_design) feats.push_back(std::move(f));
  // The shape lies within a disc about (cx, cy): r (circle), d·max(a, b) (ellipse, eq. 41),
  // |(a, b)| (super-ellipse, eq. 43: inside the box |u| <= a, |v| <= b); its centre within the
  // box of the centre's bounds.
  std::vector<double> reach;
  std::vector<std::array<Vec2, 2>> centres;
  std::vector<double> lo, hi;
  for (const Feature& f : feats) {
    binding_range(*this, f.params(), lo, hi);
    // a B-spline's control points at their bounds are no curve: it is checked at the initial
    // design (a simple closed curve); within the bounds it may come to cross itself, where its
    // distance stays defined (the nearest point's side) and `lsmbs geometry` says so
    if (f.type() == Feature::Type::kBSpline) {
      if (auto msg = f.check(f.values(initial())); !msg.empty())
        throw SetupError("design.geometry",
                         "feature '" + f.name() + "' at the initial design: " + msg, f.name());
    } else {
      for (const auto* th : {&lo, &hi})
        if (auto msg = f.check(*th); !msg.empty())
          throw SetupError(
              "design.geometry",
              "feature '" + f.name() + "' is degenerate within the design bounds: " + msg,
              f.name());
    }
    if (f.type() == Feature::Type::kBSpline) {
      // the curve lies in its control points' hull: within the box of their bounds
      Vec2 a(lo[0], lo[1]), b(hi[0], hi[1]);
      for (size_t i = 2; i + 1 < lo.size(); i += 2)
        a = a.cwiseMin(Vec2(lo[i], lo[i + 1])), b = b.cwiseMax(Vec2(hi[i], hi[i + 1]));
      reach.push_back(0);
      centres.push_back({a, b});
      continue;
    }
    reach.push_back(f.type() == Feature::Type::kCircle    ? hi[2]
                    : f.type() == Feature::Type::kEllipse ? hi[4] * std::max(hi[2], hi[3])
                                                          : std::hypot(hi[2], hi[3]));
    centres.push_back({Vec2(lo[0], lo[1]), Vec2(hi[0], hi[1])});
  }
  LevelSetNode root = region_with_non_design(spec.region, nd, static_cast<int>(feats.size()));
  BodyDesign bd;
  bd.body = &body;
  bd.num_design_features = nd;
  bd.map = std::make_unique<DesignMap>(
      body.mesh, LevelSet(std::move(feats), std::move(root), size()), spec.options);
  // A feature wholly outside its body changes nothing. One that no design variable moves never
  // will (a ring or hole drawn in another frame or unit): refused. One that a variable moves may
  // come in during an optimization: the runs warn (features_outside). One that the variables move
  // but that no values within their bounds bring in (its shape's disc never reaches an element)
  // never will either: refused as well.
  for (int k : bd.map->features_outside_mesh(initial())) {
    const auto& ls = bd.map->level_set();
    const size_t kk = static_cast<size_t>(k);
    const bool moved = !ls.feature_variables(k).empty();
    if (moved && bd.map->disc_can_reach_mesh(centres[kk][0], centres[kk][1], reach[kk])) continue;
    const Feature& f = ls.features()[kk];
    throw SetupError(
        "design.geometry",
        std::string(k >= nd ? "non-design feature '" : "feature '") + f.name() +
            "' lies wholly outside body '" + body.name + "' (it overlaps no element), and " +
            (moved ? "no values of its design variables within their bounds bring it in"
                   : "no design variable moves it") +
            ": it has no effect; check its centre and size against the mesh, in the "
            "body's frame",
        f.name());
  }
  bodies.push_back(std::move(bd));
}

int Design::variable_index(const std::string& name) const {
  for (int i = 0; i < size(); ++i)
    if (variables[i].name == name) return i;
  return -1;
}

void Design::apply(const Vec& p, ModelParams& params, std::vector<SpMat>* dmu) const {
  if (dmu) dmu->resize(bodies.size() + solid_bodies.size());
  for (size_t b = 0; b < bodies.size(); ++b)
    bodies[b].map->map(p, params.fields[bodies[b].body->field], dmu ? &(*dmu)[b] : nullptr);
  for (size_t b = 0; b < solid_bodies.size(); ++b)
    solid_bodies[b].map->map(p, params.fields[solid_bodies[b].body->field],
                             dmu ? &(*dmu)[bodies.size() + b] : nullptr);
  for (const auto& bd : bindings)
    params.scalars[bd.parameter] = bd.offset + bd.scale * p[bd.variable];
}

std::vector<ParamDirection> Design::apply_with_directions(const Vec& p, ModelParams& params) const {
  std::vector<SpMat> dmu;
  apply(p, params, &dmu);
  std::vector<ParamDirection> dirs(size());
  for (size_t b = 0; b < dmu.size(); ++b) {
    const int field =
        b < bodies.size() ? bodies[b].body->field : solid_bodies[b - bodies.size()].body->field;
    for (int k = 0; k < dmu[b].outerSize(); ++k)
      for (SpMat::InnerIterator it(dmu[b], k); it; ++it)
        dirs[it.col()].fields.push_back({field, static_cast<int>(it.row()), it.value()});
  }
  for (const auto& bd : bindings) dirs[bd.variable].scalars.emplace_back(bd.parameter, bd.scale);
  return dirs;
}

namespace {

// A tie that persists one band away along every axis: the features coincide over an area (not
// where two crossing features switch, a curve or line that μ's integral does not see).
template <class LS, class Point>
int count_ties(const LS& ls, const std::vector<Point>& nodes, const Vec& p, double eps,
               Point& first) {
  const auto values = ls.values(p);
  const double tol = 1e-7 * eps;
  int ties = 0;
  for (const Point& x : nodes) {
    if (std::abs(ls.evaluate(x, values, nullptr)) > 12 * eps) continue;  // μ does not see it
    bool tie = ls.tie_at(x, values, tol);
    for (int k = 0; k < x.size() && tie; ++k)
      tie = ls.tie_at(x + eps * Point::Unit(k), values, tol);
    if (tie && ties++ == 0) first = x;
  }
  return ties;
}

template <class Point>
std::string coincidence_message(const std::string& body, int ties, const Point& first) {
  std::string at;
  for (int k = 0; k < first.size(); ++k) at += (k ? ", " : "") + std::to_string(first[k]);
  return "body '" + body + "': two level-set features coincide at this design (" +
         std::to_string(ties) + " mesh nodes near the boundary, the first at (" + at +
         ") in the body frame): their exact min/max combination has a kink here, and the "
         "gradient is the derivative of one of them only (one-sided; central differences "
         "average the two). Move one feature, or combine them with \"ks\" "
         "(docs/case-format.md)";
}

}  // namespace

std::string Design::coincident_features(const Vec& p) const {
  for (const BodyDesign& b : bodies) {
    Vec2 first = Vec2::Zero();
    if (const int ties =
            count_ties(b.map->level_set(), b.body->mesh.nodes, p, b.map->epsilon(), first))
      return coincidence_message(b.body->name, ties, first);
  }
  for (const SolidBodyDesign& b : solid_bodies) {
    Vec3 first = Vec3::Zero();
    if (const int ties =
            count_ties(b.map->level_set(), b.body->mesh.nodes, p, b.map->epsilon(), first))
      return coincidence_message(b.body->name, ties, first);
  }
  return {};
}

std::string Design::features_outside(const Vec& p) const {
  std::string w;
  const auto add = [&](const std::string& body, const std::vector<std::string>& outside) {
    if (outside.empty()) return;
    std::string names;
    for (const auto& n : outside) names += (names.empty() ? "'" : ", '") + n + "'";
    w += (w.empty() ? "" : "; ") + std::string("body '") + body + "': level-set " +
         (outside.size() == 1 ? "feature " : "features ") + names +
         (outside.size() == 1 ? " lies" : " lie") +
         " wholly outside the body at this design (overlapping no element), with no effect on "
         "it until a design variable moves it in (check the centre and size against the mesh, "
         "in the body's frame)";
  };
  for (const BodyDesign& b : bodies) {
    std::vector<std::string> names;
    for (int f : b.map->features_outside_mesh(p))
      names.push_back(b.map->level_set().features()[static_cast<size_t>(f)].name());
    add(b.body->name, names);
  }
  for (const SolidBodyDesign& b : solid_bodies) {
    std::vector<std::string> names;
    for (int f : b.map->features_outside_mesh(p))
      names.push_back(b.map->level_set().features()[static_cast<size_t>(f)].name());
    add(b.body->name, names);
  }
  return w;
}

std::string Design::idle_variables() const {
  std::vector<char> drives(variables.size(), 0);
  for (const auto& b : bindings) drives[static_cast<size_t>(b.variable)] = 1;
  const auto mark = [&](const std::vector<ParamBinding>& params) {
    for (const auto& pb : params)
      if (pb.variable >= 0 && pb.scale != 0) drives[static_cast<size_t>(pb.variable)] = 1;
  };
  for (const BodyDesign& b : bodies)
    for (const auto& f : b.map->level_set().features()) mark(f.params());
  for (const SolidBodyDesign& b : solid_bodies)
    for (const auto& f : b.map->level_set().features()) mark(f.params());
  std::string names;
  int n = 0;
  for (size_t k = 0; k < drives.size(); ++k)
    if (!drives[k]) {
      names += (names.empty() ? "'" : ", '") + variables[k].name + "'";
      ++n;
    }
  if (names.empty()) return {};
  return std::string(n == 1 ? "design variable " : "design variables ") + names +
         (n == 1 ? " drives" : " drive") +
         " nothing: no feature parameter (with a nonzero scale) and no entry of \"parameters\" is "
         "bound to " +
         (n == 1 ? "it" : "them") +
         ", so the gradient is zero there whatever the design and an optimizer leaves " +
         (n == 1 ? "it" : "them") + " where " + (n == 1 ? "it starts" : "they start");
}

double Design::mass_gradient(const BodyDesign& b, const SpMat& dmu, const ModelParams& params,
                             Vec& grad) {
  const double rt = params.scalars[b.body->rho_param] * params.scalars[b.body->thickness_param];
  const auto& A = b.map->element_areas();
  grad.setZero(dmu.cols());
  for (int k = 0; k < dmu.outerSize(); ++k)
    for (SpMat::InnerIterator it(dmu, k); it; ++it) grad[it.col()] += rt * A[it.row()] * it.value();
  return b.body->mass(params);
}

}  // namespace lsmbs
