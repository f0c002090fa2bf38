#include "lsmbs/runs/shape.hpp"

#include <algorithm>
#include <cmath>

#include "lsmbs/fem/element_types.hpp"

namespace lsmbs {
namespace {

nlohmann::json point(const Vec2& x) { return nlohmann::json::array({x.x(), x.y()}); }

nlohmann::json node_json(const LevelSetNode& n) {
  switch (n.op) {
    case LevelSetNode::Op::kFeature:
      return {{"op", "feature"}, {"feature", n.feature}};
    case LevelSetNode::Op::kNot:
      return {{"op", "not"}, {"children", nlohmann::json::array({node_json(n.children[0])})}};
    default: {
      nlohmann::json c = nlohmann::json::array();
      for (const auto& k : n.children) c.push_back(node_json(k));
      return {{"op", n.op == LevelSetNode::Op::kAnd ? "and" : "or"}, {"ks", n.ks}, {"children", c}};
    }
  }
}

const char* type_name(Feature::Type t) {
  return t == Feature::Type::kCircle         ? "circle"
         : t == Feature::Type::kEllipse      ? "ellipse"
         : t == Feature::Type::kSuperEllipse ? "super_ellipse"
                                             : "bspline";
}

nlohmann::json vec3(const Vec3& x) { return nlohmann::json::array({x.x(), x.y(), x.z()}); }

}  // namespace

nlohmann::json solid_shape_json(const SolidBodyDesign& b, const Vec& p, const ModelParams& params) {
  const SolidBody& body = *b.body;
  const SolidMesh& mesh = body.mesh;
  Vec3 lo = mesh.nodes.front(), hi = lo;
  for (const Vec3& x : mesh.nodes) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  double V = 0;
  for (double v : b.map->element_volumes()) V += v;
  const double box = (hi - lo).prod();
  nlohmann::json domain = {{"type", "mesh"}};
  if (std::abs(V - box) <= 1e-9 * box)
    domain = {{"type", "box"}, {"lo", vec3(lo)}, {"hi", vec3(hi)}};
  const LevelSet3& ls = b.map->level_set();
  nlohmann::json features = nlohmann::json::array();
  for (const Feature3& f : ls.features()) {
    nlohmann::json par = nlohmann::json::object();
    const auto v = f.values(p);
    const auto names = Feature3::parameter_names(f.type(), f.profile());
    for (size_t i = 0; i < v.size(); ++i) par[names[i]] = v[i];
    const Mat3& A = f.frame().axes;
    nlohmann::json entry = {{"name", f.name()},
                            {"type", Feature3::type_names()[static_cast<size_t>(f.type())]},
                            {"hole", f.hole()},
                            {"params", par},
                            {"frame",
                             {{"origin", vec3(f.frame().origin)},
                              {"u", vec3(A.col(0))},
                              {"v", vec3(A.col(1))},
                              {"w", vec3(A.col(2))}}}};
    if (f.type() == Feature3::Type::kPocket || f.type() == Feature3::Type::kThroughHole)
      entry["profile"] = type_name(f.profile());
    features.push_back(entry);
  }
  const auto scalar = [&](int i) { return params.scalars[static_cast<size_t>(i)]; };
  return {{"body", body.name},
          {"kind", "solid"},
          {"frame", "ground coordinates at t = 0; lengths in m"},
          {"domain", domain},
          {"features", features},
          {"region", node_json(ls.root())},
          {"material",
           {{"E", scalar(body.E_param)},
            {"nu", scalar(body.nu_param)},
            {"rho", scalar(body.rho_param)}}},
          {"mu_min", b.map->options().mu_min}};
}

nlohmann::json shape_json(const BodyDesign& b, const Vec& p, const ModelParams& params) {
  const FlexibleBody& body = *b.body;
  const Mesh2D& mesh = body.mesh;
  nlohmann::json outline = nlohmann::json::array();
  for (const auto& loop : mesh.boundary_loops()) {
    nlohmann::json l = nlohmann::json::array();
    for (int k : loop) l.push_back(point(mesh.nodes[static_cast<size_t>(k)]));
    outline.push_back(l);
  }
  const LevelSet& ls = b.map->level_set();
  nlohmann::json features = nlohmann::json::array();
  for (const Feature& f : ls.features()) {
    nlohmann::json par = nlohmann::json::object();
    const auto v = f.values(p);
    for (size_t i = 0; i < v.size(); ++i) par[f.parameter_name(i)] = v[i];
    nlohmann::json entry = {
        {"name", f.name()}, {"type", type_name(f.type())}, {"hole", f.hole()}, {"params", par}};
    if (f.type() == Feature::Type::kBSpline) {  // closed, uniform, cubic (ClosedBSpline)
      nlohmann::json pts = nlohmann::json::array();
      for (size_t i = 0; i + 1 < v.size(); i += 2) pts.push_back({v[i], v[i + 1]});
      entry["control_points"] = pts;
      entry["degree"] = 3;
    }
    features.push_back(entry);
  }
  nlohmann::json sets = nlohmann::json::object();
  for (const auto& [name, nodes] : mesh.node_sets) {
    nlohmann::json s = nlohmann::json::array();
    for (int k : nodes) s.push_back(point(mesh.nodes[static_cast<size_t>(k)]));
    sets[name] = s;
  }
  std::vector<double> h;
  for (int e = 0; e < mesh.num_elements(); ++e)
    h.push_back(std::sqrt(element_type(mesh.cells[static_cast<size_t>(e)].type)
                              .shape->area(mesh.cell_nodes(e).data())));
  std::nth_element(h.begin(), h.begin() + static_cast<long>(h.size() / 2), h.end());
  const auto scalar = [&](int i) { return params.scalars[static_cast<size_t>(i)]; };
  return {{"body", body.name},
          {"frame", "the body's mesh frame; lengths in m"},
          {"outline", outline},
          {"features", features},
          {"region", node_json(ls.root())},
          {"node_sets", sets},
          {"thickness", scalar(body.thickness_param)},
          {"material",
           {{"E", scalar(body.E_param)},
            {"nu", scalar(body.nu_param)},
            {"rho", scalar(body.rho_param)}}},
          {"element_size", h.empty() ? 0.0 : h[h.size() / 2]},
          {"mu_min", b.map->options().mu_min}};
}

}  // namespace lsmbs
