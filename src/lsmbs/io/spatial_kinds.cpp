// The kinds of spatial cases ("dimension": 3): the joints, drivers, forces and measures of
// spatial rigid bodies (mbs/spatial*.hpp, responses/spatial_measure.hpp), read through the
// ModelBuilder's spatial calls. Points are given where they are at t = 0, in ground coordinates
// ("at"), with the body they belong to; axes likewise. docs/case-format.md, "Spatial cases".
#include "lsmbs/io/model_kinds.hpp"
#include "lsmbs/responses/spatial_measure.hpp"

namespace lsmbs {

namespace {

using K = KeyType;

KindKey req(std::string name, KeyType t, std::string doc) {
  return {std::move(name), t, true, true, "", std::move(doc)};
}
KindKey opt(std::string name, KeyType t, std::string doc) {
  return {std::move(name), t, false, false, "", std::move(doc)};
}

SpatialJointOptions joint_options(const JsonReader& r, SpatialJointKind kind) {
  SpatialJointOptions o;
  o.at = r.vec3("at");
  const bool axial = kind != SpatialJointKind::kSpherical && kind != SpatialJointKind::kWeld;
  if (kind == SpatialJointKind::kPlanar)
    o.axis = r.vec3("normal");
  else if (axial)
    o.axis = r.vec3("axis");
  if (kind == SpatialJointKind::kUniversal) o.axis_b = r.vec3("axis_b");
  return o;
}

// A driver's law less its value at assembly (the joint coordinates are zero there).
std::shared_ptr<const TimeLaw> shifted(std::shared_ptr<const TimeLaw> law, double offset) {
  if (offset == 0 || !law) return law;
  return std::make_shared<ShiftedLaw>(std::move(law), -offset);
}

ModelKind joint(const char* type, SpatialJointKind kind, const char* doc) {
  std::vector<KindKey> keys = {req("a", K::kName, "the first body, or \"ground\""),
                               req("b", K::kName, "the second body, or \"ground\""),
                               req("at", K::kVec3, "the joint's point at t = 0 [m]")};
  if (kind == SpatialJointKind::kPlanar)
    keys.push_back(req("normal", K::kVec3, "the plane's normal (any length)"));
  else if (kind == SpatialJointKind::kUniversal) {
    keys.push_back(req("axis", K::kVec3, "the cross's axis fixed in a"));
    keys.push_back(req("axis_b", K::kVec3, "the cross's axis fixed in b, ⟂ axis"));
  } else if (kind != SpatialJointKind::kSpherical && kind != SpatialJointKind::kWeld)
    keys.push_back(req("axis", K::kVec3, "the joint's axis (any length)"));
  return {"joints", type, doc, keys,
          [kind](KindReader& k, const JsonReader& r, const std::string& name) {
            const std::string a = r.string("a"), b = r.string("b");
            const SpatialJointOptions o = joint_options(r, kind);
            k.at_entry(r, [&] { k.builder().spatial_joint(name, kind, a, b, o); });
          }};
}

std::vector<ModelKind> joints() {
  using J = SpatialJointKind;
  return {
      joint("spherical", J::kSpherical, "x_b = x_a: a ball joint (3 equations)"),
      joint("universal", J::kUniversal,
            "spherical, and the cross's two axes stay perpendicular (4 equations)"),
      joint("revolute", J::kRevolute,
            "spherical, and the axis fixed in a and in b stay aligned (5 equations; its "
            "angle is a joint coordinate)"),
      joint("cylindrical", J::kCylindrical,
            "b turns about and slides along the axis (4 equations; its angle is a joint "
            "coordinate)"),
      joint("prismatic", J::kPrismatic, "b slides along the axis without turning (5 equations)"),
      joint("planar", J::kPlanar, "b moves in the plane of the normal through the point (3)"),
      joint("weld", J::kWeld, "b is fixed to a (6 equations)"),
      joint("inline", J::kInline,
            "x_b stays on the line through x_a along the axis, turning freely (2 equations; "
            "closes a loop of a planar mechanism without redundant equations)"),
      {"joints",
       "solid_connection",
       "every node of a solid body's node set keeps its offset in a rigid body's principal "
       "frame, or (body \"ground\") stays where it is (3 equations per node)",
       {req("solid", K::kName, "the solid body"),
        req("node_set", K::kName, "its node set (a box: xmin, xmax, ymin, ymax, zmin, zmax)"),
        req("body", K::kName, "a rigid body, or \"ground\"")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string solid = r.string("solid"), set = r.string("node_set"),
                           body = r.string("body");
         k.at_entry(r, [&] { k.builder().solid_connection(name, solid, set, body); });
       }},
      {"joints",
       "rotation_driver",
       "θ − s(t) + offset = 0 on the angle of a revolute or cylindrical joint (θ = 0 at t = 0)",
       {req("joint", K::kName, "the joint"), req("law", K::kLaw, "s(t) [rad]"),
        opt("offset", K::kNumber, "s(t) where θ = 0, at assembly (default 0)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string j = r.string("joint");
         auto l = shifted(k.law(r.child("law")), r.number("offset", 0.0));
         k.at_entry(r, [&] { k.builder().joint_rotation_driver(name, j, l); });
       }},
      {"joints",
       "translation_driver",
       "a₃·(x_b − x_a) − s(t) + offset = 0 along a prismatic or cylindrical joint's axis (0 at t = "
       "0)",
       {req("joint", K::kName, "the joint"), req("law", K::kLaw, "s(t) [m]"),
        opt("offset", K::kNumber, "s(t) where the translation is 0 (default 0)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string j = r.string("joint");
         auto l = shifted(k.law(r.child("law")), r.number("offset", 0.0));
         k.at_entry(r, [&] { k.builder().joint_translation_driver(name, j, l); });
       }},
  };
}

// A load's three components: a constant vector under `vector_key`, or time laws under the
// three component keys (each default zero).
std::array<std::shared_ptr<const TimeLaw>, 3> components(KindReader& k, const JsonReader& r,
                                                         const std::string& vector_key,
                                                         const std::array<const char*, 3>& keys) {
  std::array<std::shared_ptr<const TimeLaw>, 3> laws;
  if (r.has(vector_key)) {
    for (const char* c : keys)
      if (r.has(c)) r.fail(c, "give either " + vector_key + " or the component laws, not both");
    const Vec3 v = r.vec3(vector_key);
    for (int i = 0; i < 3; ++i) laws[static_cast<size_t>(i)] = std::make_shared<ConstantLaw>(v[i]);
    return laws;
  }
  for (int i = 0; i < 3; ++i)
    laws[static_cast<size_t>(i)] =
        r.has(keys[static_cast<size_t>(i)])
            ? k.law(r.child(keys[static_cast<size_t>(i)]))
            : std::shared_ptr<const TimeLaw>(std::make_shared<ConstantLaw>(0.0));
  return laws;
}

SpatialLoad::Frame load_frame(const JsonReader& r) {
  return r.one_of("frame", {"ground", "body"}, "ground") == "body" ? SpatialLoad::Frame::kBody
                                                                   : SpatialLoad::Frame::kGround;
}

std::vector<ModelKind> forces() {
  return {
      {"forces",
       "point_force",
       "scale · F at a body point, in the ground frame or the body's principal frame",
       {req("body", K::kName, "the body"), req("at", K::kVec3, "the point at t = 0 [m]"),
        opt("force", K::kVec3, "a constant force [N] (or fx, fy, fz)"),
        opt("fx", K::kLaw, "F₁(t) [N] (default zero)"), opt("fy", K::kLaw, "F₂(t) [N]"),
        opt("fz", K::kLaw, "F₃(t) [N]"),
        opt("frame", K::kName, "\"ground\" (default) or \"body\" (turns with the body)"),
        opt("scale", K::kNumber, "factor (default 1)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string body = r.string("body");
         const Vec3 at = r.vec3("at");
         auto laws = components(k, r, "force", {"fx", "fy", "fz"});
         const auto frame = load_frame(r);
         const double scale = r.number("scale", 1.0);
         k.at_entry(r, [&] {
           k.builder().spatial_load(name, SpatialLoad::Kind::kForce, body, at, laws, frame, scale);
         });
       }},
      {"forces",
       "torque",
       "scale · T on a body, in the ground frame or the body's principal frame",
       {req("body", K::kName, "the body"),
        opt("torque", K::kVec3, "a constant torque [N m] (or tx, ty, tz)"),
        opt("tx", K::kLaw, "T₁(t) [N m] (default zero)"), opt("ty", K::kLaw, "T₂(t) [N m]"),
        opt("tz", K::kLaw, "T₃(t) [N m]"),
        opt("frame", K::kName, "\"ground\" (default) or \"body\""),
        opt("scale", K::kNumber, "factor (default 1)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string body = r.string("body");
         auto laws = components(k, r, "torque", {"tx", "ty", "tz"});
         const auto frame = load_frame(r);
         const double scale = r.number("scale", 1.0);
         k.at_entry(r, [&] {
           k.builder().spatial_load(name, SpatialLoad::Kind::kTorque, body, Vec3::Zero(), laws,
                                    frame, scale);
         });
       }},
      {"forces",
       "spring_damper",
       "tension k (l − l0) + c l̇ between two body points (either may be ground)",
       {req("a", K::kName, "a body or \"ground\""), req("a_at", K::kVec3, "its point at t = 0"),
        req("b", K::kName, "a body or \"ground\""), req("b_at", K::kVec3, "its point at t = 0"),
        req("stiffness", K::kNonNegative, "k [N/m]"),
        opt("damping", K::kNonNegative, "c [N s/m] (default 0)"),
        opt("free_length", K::kNonNegative, "l0 [m] (default: the initial distance)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string a = r.string("a"), b = r.string("b");
         const Vec3 pa = r.vec3("a_at"), pb = r.vec3("b_at");
         SpringOptions o;
         o.stiffness = r.non_negative("stiffness");
         o.damping = r.non_negative("damping", 0.0);
         if (r.has("free_length")) o.free_length = r.non_negative("free_length");
         k.at_entry(r, [&] { k.builder().spatial_spring_damper(name, a, pa, b, pb, o); });
       }},
      {"forces",
       "rotational_spring_damper",
       "moment k (θ − θ0) + c θ̇ on a revolute or cylindrical joint's angle",
       {req("joint", K::kName, "the joint"), req("stiffness", K::kNonNegative, "k [N m/rad]"),
        opt("damping", K::kNonNegative, "c [N m s/rad] (default 0)"),
        opt("free_angle", K::kNumber, "θ0 [rad] (default 0: the angle at t = 0)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string j = r.string("joint");
         RotationalSpringOptions o;
         o.stiffness = r.non_negative("stiffness");
         o.damping = r.non_negative("damping", 0.0);
         if (r.has("free_angle")) o.free_angle = r.number("free_angle");
         k.at_entry(r, [&] { k.builder().joint_spring_damper(name, j, o); });
       }},
  };
}

// The body named under "body" and the principal-frame offset of the point at "at" (t = 0).
const SpatialRigidBody& body_of(KindReader& k, const JsonReader& r) {
  const std::string b = r.string("body");
  return k.at_key(r, "body", [&]() -> const SpatialRigidBody& { return k.builder().spatial(b); });
}
Vec3 offset_of(const SpatialRigidBody& b, const JsonReader& r) {
  return b.orientation0.transpose() * (r.vec3("at", b.position0) - b.position0);
}

const SpatialJointInfo& joint_of(KindReader& k, const JsonReader& r) {
  const std::string j = r.string("joint");
  return k.at_key(r, "joint",
                  [&]() -> const SpatialJointInfo& { return k.builder().spatial_joint_info(j); });
}

// A point {"body": name, "at": [x, y, z]} (at: t = 0; default the centre of mass) or
// {"ground": [x, y, z]}, under key.
SpatialPoint spatial_point(KindReader& k, const JsonReader& parent, const char* key) {
  const JsonReader r = parent.child(key);
  SpatialPoint pt;
  if (r.has("ground")) {
    pt.d = r.vec3("ground");
  } else {
    const SpatialRigidBody& b = body_of(k, r);
    pt.dof0 = b.dof0;
    pt.d = offset_of(b, r);
  }
  r.finish();
  return pt;
}

const SolidBody& solid_of(KindReader& k, const JsonReader& r) {
  const std::string b = r.string("body");
  return k.at_key(r, "body", [&]() -> const SolidBody& { return k.builder().solid(b); });
}

/// The nodes of the solid body's node set named by r[key].
const std::vector<int>& node_set_of(const SolidBody& sb, const JsonReader& r, const char* key) {
  const std::string set = r.string(key);
  const auto it = sb.mesh.node_sets.find(set);
  if (it == sb.mesh.node_sets.end())
    r.fail(key, "solid body '" + sb.name + "' has no node set '" + set + "' (it has " +
                    sb.mesh.node_set_names() + ")");
  return it->second;
}

std::vector<int> node_dofs(const SolidBody& sb, const std::vector<int>& nodes) {
  std::vector<int> dofs;
  for (int n : nodes) dofs.push_back(sb.node_dof(n));
  return dofs;
}

Vec3 mean_position(const SolidBody& sb, const std::vector<int>& nodes) {
  Vec3 x = Vec3::Zero();
  for (int n : nodes) x += sb.mesh.nodes[static_cast<size_t>(n)];
  return x / static_cast<double>(nodes.size());
}

std::vector<ModelKind> measures() {
  const KindKey body = req("body", K::kName, "the body");
  const KindKey at = opt("at", K::kVec3, "the point at t = 0 (default: the centre of mass) [m]");
  const KindKey joint = req("joint", K::kName, "the joint");
  return {
      {"measures",
       "position",
       "a body point's position, x, y, z [m]",
       {body, at},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SpatialRigidBody& b = body_of(k, r);
         k.add_measure(std::make_unique<SpatialPointMeasure>(
             name, SpatialPointMeasure::Kind::kPosition, b.dof0, offset_of(b, r)));
       }},
      {"measures",
       "velocity",
       "a body point's velocity, x, y, z [m/s]",
       {body, at},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SpatialRigidBody& b = body_of(k, r);
         k.add_measure(std::make_unique<SpatialPointMeasure>(
             name, SpatialPointMeasure::Kind::kVelocity, b.dof0, offset_of(b, r)));
       }},
      {"measures",
       "body_axis",
       "the orientation of a body as the image of a body-fixed direction, x, y, z [1]",
       {body, req("axis", K::kVec3, "the direction at t = 0 (any length; reported unit)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SpatialRigidBody& b = body_of(k, r);
         const Vec3 u = r.vec3("axis");
         if (!(u.norm() > 0)) r.fail("axis", "expected a non-zero direction");
         k.add_measure(std::make_unique<BodyAxisMeasure>(
             name, b.dof0, b.orientation0.transpose() * u.normalized()));
       }},
      {"measures",
       "angular_velocity",
       "a body's angular velocity, x, y, z, in the ground or its principal frame [rad/s]",
       {body, opt("frame", K::kName, "\"ground\" (default) or \"body\"")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SpatialRigidBody& b = body_of(k, r);
         const bool body_frame = r.one_of("frame", {"ground", "body"}, "ground") == "body";
         k.add_measure(std::make_unique<SpatialAngularVelocityMeasure>(name, b.dof0, body_frame));
       }},
      {"measures",
       "joint_angle",
       "the rotation of a revolute or cylindrical joint from t = 0 [rad]",
       {joint},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SpatialJointInfo& j = joint_of(k, r);
         if (j.theta_dof < 0) r.fail("joint", "expected a revolute or cylindrical joint");
         k.add_measure(std::make_unique<AngleMeasure>(name, j.theta_dof));
       }},
      {"measures",
       "joint_rate",
       "the rate of a revolute or cylindrical joint's angle [rad/s]",
       {joint},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SpatialJointInfo& j = joint_of(k, r);
         if (j.theta_dof < 0) r.fail("joint", "expected a revolute or cylindrical joint");
         k.add_measure(std::make_unique<AngularVelocityMeasure>(name, j.theta_dof));
       }},
      {"measures",
       "joint_translation",
       "the translation of a prismatic or cylindrical joint from t = 0 [m]",
       {joint},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SpatialJointInfo& j = joint_of(k, r);
         if (!spatial_joint_slides(j.kind))
           r.fail("joint", "expected a prismatic or cylindrical joint");
         const auto body = [&](const std::string& n) {
           if (n == "ground") return std::pair<SpatialBody, SpatialPose>{};
           const SpatialRigidBody& b = k.builder().spatial(n);
           return std::pair<SpatialBody, SpatialPose>{SpatialBody{b.dof0},
                                                      {b.position0, b.orientation0}};
         };
         const auto [ba, pa] = body(j.a);
         const auto [bb, pb] = body(j.b);
         k.add_measure(std::make_unique<JointTranslationMeasure>(
             name, make_spatial_translation_driver(ba, pa, bb, pb, j.frame, nullptr)));
       }},
      {"measures",
       "constraint_force",
       "the multipliers λ of a joint's equations [N or N m]",
       {joint},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string j = r.string("joint");
         k.at_key(r, "joint", [&] { return k.builder().joint_equations(j); });
         k.add_constraint_force(name, j);
       }},
      {"measures",
       "distance",
       "|x_b − x_a| between two points of rigid bodies or the ground [m]",
       {req("a", K::kJson, "{\"body\": name, \"at\": [x, y, z]} or {\"ground\": [x, y, z]}"),
        req("b", K::kJson, "the other point, likewise")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         k.add_measure(std::make_unique<SpatialDistanceMeasure>(name, spatial_point(k, r, "a"),
                                                                spatial_point(k, r, "b"), 0.0));
       }},
      {"measures",
       "node_set_position",
       "the mean position of a solid body's node set, x, y, z [m]",
       {req("body", K::kName, "the solid body"), req("node_set", K::kName, "its node set")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SolidBody& sb = solid_of(k, r);
         k.add_measure(
             std::make_unique<NodeSetMeasure>(name, node_dofs(sb, node_set_of(sb, r, "node_set"))));
       }},
      {"measures",
       "elongation",
       "the distance between the mean positions of two node sets minus its value at t = 0 [m]",
       {req("body", K::kName, "the solid body"), req("a", K::kName, "one node set"),
        req("b", K::kName, "the other node set")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SolidBody& sb = solid_of(k, r);
         const auto &a = node_set_of(sb, r, "a"), &b = node_set_of(sb, r, "b");
         const double d0 = (mean_position(sb, b) - mean_position(sb, a)).norm();
         if (!(d0 > 0))
           r.fail("b", "the node sets' mean positions coincide: their distance has no direction");
         k.add_measure(std::make_unique<NodeSetDistanceMeasure>(name, node_dofs(sb, a),
                                                                node_dofs(sb, b), d0));
       }},
      {"measures",
       "strain_energy",
       "the strain energy of the flexible and solid bodies [J]",
       {},
       [](KindReader& k, const JsonReader&, const std::string& name) {
         k.add_measure(std::make_unique<StrainEnergyMeasure>(name));
       }},
      {"measures",
       "mass",
       "the mass of a solid body, Σ_e μ_e ρ V_e [kg] (a design's material volume times ρ)",
       {req("body", K::kName, "the solid body")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SolidBody& sb = solid_of(k, r);
         k.add_measure(std::make_unique<SolidMassMeasure>(name, &sb));
       }},
      {"measures", "stress",
       "aggregated relaxed von Mises stress of a solid body, s_e = μ_e^q σ_vM [Pa]",
       stress_keys("the solid body", true),
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const SolidBody& sb = solid_of(k, r);
         k.add_measure(std::make_unique<StressMeasure>(name, &sb, stress_options(r)));
       }},
      {"measures",
       "combination",
       "c0 + Σ w_i · (a column of an earlier measure)",
       {req("terms", K::kJson, "[{\"measure\": column, \"weight\": w}, …]"),
        opt("constant", K::kNumber, "c0 (default 0)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         k.add_measure(k.combination(r, name));
       }},
      {"measures",
       "kinetic_energy",
       "of the whole model [J]",
       {},
       [](KindReader& k, const JsonReader&, const std::string& name) {
         k.add_measure(std::make_unique<KineticEnergyMeasure>(name));
       }},
  };
}

}  // namespace

const std::vector<ModelKind>& spatial_model_kinds() {
  static const std::vector<ModelKind> kinds = [] {
    std::vector<ModelKind> all;
    for (auto part : {joints(), forces(), measures()})
      for (auto& k : part) all.push_back(std::move(k));
    return all;
  }();
  return kinds;
}

const ModelKind* find_spatial_kind(const std::string& section, const std::string& type) {
  return find_kind_in(spatial_model_kinds(), section, type);
}

std::vector<std::string> spatial_kind_types(const std::string& section) {
  return kind_types_in(spatial_model_kinds(), section);
}

}  // namespace lsmbs
