#include "lsmbs/io/model_kinds.hpp"

#include <optional>

namespace lsmbs {

const char* key_type_name(KeyType t) {
  switch (t) {
    case KeyType::kNumber:
      return "number";
    case KeyType::kNonNegative:
      return "non-negative number";
    case KeyType::kPositive:
      return "positive number";
    case KeyType::kInteger:
      return "integer";
    case KeyType::kBoolean:
      return "boolean";
    case KeyType::kName:
      return "name";
    case KeyType::kVec2:
      return "[x, y]";
    case KeyType::kVec3:
      return "[x, y, z]";
    case KeyType::kPoint:
      return "point";
    case KeyType::kPointOrGround:
      return "point or \"ground\"";
    case KeyType::kLaw:
      return "time law";
    case KeyType::kTable:
      return "table";
    case KeyType::kParameter:
      return "feature parameter";
    case KeyType::kJson:
      return "object";
  }
  return "?";
}

void KindReader::at_entry(const JsonReader& r, const std::function<void()>& call) {
  try {
    call();
  } catch (const ModelError& e) {
    if (e.field().empty()) r.fail(e.message());
    r.fail(e.field(), e.message());
  }
}

namespace {

using K = KeyType;

// Keys by how they are given: required and positional, optional and positional, keyword-only.
KindKey pos(std::string name, KeyType t, std::string doc) {
  return {std::move(name), t, true, true, "", std::move(doc)};
}
KindKey opt_pos(std::string name, KeyType t, std::string doc, std::string python_default = "") {
  return {std::move(name), t, false, true, std::move(python_default), std::move(doc)};
}
KindKey kw(std::string name, KeyType t, std::string doc, bool required = false) {
  return {std::move(name), t, required, false, "", std::move(doc)};
}

std::optional<Vec2> optional_vec2(const JsonReader& r, const std::string& key) {
  if (!r.has(key)) return std::nullopt;
  return r.vec2(key);
}

// ---------------------------------------------------------------- joints and drivers
std::vector<ModelKind> joints() {
  return {
      {"joints",
       "revolute",
       "p_a = p_b: a pin between two bodies, or a body and the ground",
       {pos("a", K::kPoint, "the point of the first body"),
        opt_pos("b", K::kPointOrGround,
                "the point it is pinned to (default, or \"ground\": the ground point at a's "
                "initial position)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const Point a = k.point(r.child("a"));
         std::optional<Point> b;  // none: the builder's default, ground at a's initial position
         if (r.has("b")) {
           const JsonReader rb = r.child("b");
           if (!(rb.is_string() && rb.as_string() == "ground")) b = k.point(rb);
         }
         k.at_entry(r, [&] { k.builder().revolute(name, a, b); });
       }},
      {"joints",
       "prismatic",
       "point a slides on a line of the given direction",
       {pos("a", K::kPoint, "the sliding point"),
        pos("direction", K::kVec2, "direction of the line (any length)"),
        kw("through", K::kVec2, "a point of the line (default: the initial position of a)"),
        kw("lock_rotation", K::kBoolean,
           "also hold the body's angle at its initial value (default true; rigid bodies)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const Point a = k.point(r.child("a"));
         const Vec2 u = r.vec2("direction");
         PrismaticOptions o;
         o.through = optional_vec2(r, "through");
         o.lock_rotation = r.boolean("lock_rotation", true);
         k.at_entry(r, [&] { k.builder().prismatic(name, a, u, o); });
       }},
      {"joints",
       "rigid_connection",
       "every node of a node set keeps its initial offset in a rigid body's frame",
       {pos("rigid", K::kName, "the rigid body"), pos("flexible", K::kName, "the flexible body"),
        pos("node_set", K::kName, "the flexible body's node set")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string rigid = r.string("rigid"), flexible = r.string("flexible"),
                           set = r.string("node_set");
         k.at_entry(r, [&] { k.builder().rigid_connection(name, rigid, flexible, set); });
       }},
      {"joints",
       "clamp",
       "every node of a node set stays at its initial position",
       {pos("flexible", K::kName, "the flexible body"),
        pos("node_set", K::kName, "the flexible body's node set")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string flexible = r.string("flexible"), set = r.string("node_set");
         k.at_entry(r, [&] { k.builder().clamp(name, flexible, set); });
       }},
      {"joints",
       "rotation_driver",
       "θ_body − θ_relative_to − s(t) = 0",
       {pos("body", K::kName, "the rigid body driven"), pos("law", K::kLaw, "s(t) [rad]"),
        opt_pos("relative_to", K::kName, "a rigid body, or \"ground\" (default)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string body = r.string("body");
         const std::string rel = r.string("relative_to", "ground");
         auto l = k.law(r.child("law"));
         k.at_entry(r, [&] { k.builder().rotation_driver(name, body, l, rel); });
       }},
      {"joints",
       "translation_driver",
       "u·(p − x0) − s(t) = 0 along a fixed direction u",
       {pos("point", K::kPoint, "the driven point"), pos("direction", K::kVec2, "u (any length)"),
        pos("law", K::kLaw, "s(t) [m]"),
        opt_pos("through", K::kVec2, "x0 (default: the initial position of the point)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const Point a = k.point(r.child("point"));
         const Vec2 u = r.vec2("direction");
         const std::optional<Vec2> through = optional_vec2(r, "through");
         auto l = k.law(r.child("law"));
         k.at_entry(r, [&] { k.builder().translation_driver(name, a, u, l, through); });
       }},
  };
}

// ---------------------------------------------------------------- forces
void read_pressure(KindReader& k, const JsonReader& r, const std::string& name) {
  const Point p = k.point(r.child("point"));
  const Vec2 u = r.vec2("direction");
  const double area = r.positive("area");
  const JsonReader tr = r.child("table");
  Table1D t = k.table(tr);
  tr.finish();  // a misspelt table option (e.g. "x_scal") is an error, not ignored
  PressureArgument arg;
  if (r.has("argument")) {
    const JsonReader a = r.child("argument");
    if (a.is_string()) {
      if (a.as_string() != "time")
        a.fail("expected \"time\" or {\"angle_of\": body, \"offset\": rad}");
    } else {
      arg.angle_of = a.string("angle_of");
      arg.offset = a.number("offset", 0.0);
      a.finish();
    }
  }
  if (arg.angle_of.empty()) arg.offset = r.number("time_offset", 0.0);
  k.at_entry(r, [&] { k.builder().pressure(name, p, u, area, std::move(t), arg); });
}

std::vector<ModelKind> forces() {
  return {
      {"forces",
       "point_force",
       "scale · F at a point, in the inertial frame: a constant force, or time laws fx and fy",
       {pos("point", K::kPoint, "where"),
        opt_pos("force", K::kVec2, "a constant force [N] (or fx, fy)"),
        kw("fx", K::kLaw, "Fx(t) [N] (default zero)"),
        kw("fy", K::kLaw, "Fy(t) [N] (default zero)"),
        kw("scale", K::kNumber, "factor (default 1)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const Point p = k.point(r.child("point"));
         std::shared_ptr<const TimeLaw> fx, fy;  // null: zero
         const std::optional<Vec2> f = optional_vec2(r, "force");
         if (!f) {
           if (r.has("fx")) fx = k.law(r.child("fx"));
           if (r.has("fy")) fy = k.law(r.child("fy"));
         }
         const double scale = r.number("scale", 1.0);
         k.at_entry(r, [&] {
           if (f)
             k.builder().point_force(name, p, *f, scale);
           else
             k.builder().point_force(name, p, fx, fy, scale);
         });
       }},
      {"forces",
       "spring_damper",
       "a linear spring and damper between two points",
       {pos("a", K::kPoint, "one end"), pos("b", K::kPoint, "the other end"),
        kw("stiffness", K::kNonNegative, "[N/m]", true),
        kw("damping", K::kNonNegative, "[N s/m] (default 0)"),
        kw("free_length", K::kNonNegative, "[m] (default: the initial distance of the ends)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const Point a = k.point(r.child("a")), b = k.point(r.child("b"));
         SpringOptions o;
         o.stiffness = r.non_negative("stiffness");
         o.damping = r.non_negative("damping", 0.0);
         if (r.has("free_length")) o.free_length = r.non_negative("free_length");
         k.at_entry(r, [&] { k.builder().spring_damper(name, a, b, o); });
       }},
      {"forces",
       "pressure",
       "a pressure P(s) × area along a fixed direction; s is the time or a body's angle",
       {pos("point", K::kPoint, "where the force acts"),
        pos("direction", K::kVec2, "of the force (any length)"), pos("area", K::kPositive, "[m²]"),
        pos("table", K::kTable, "P(s) [Pa]"),
        opt_pos("argument", K::kJson,
                "\"time\" (default) or {\"angle_of\": body, \"offset\": rad}"),
        opt_pos("time_offset", K::kNumber, "s = t + offset [s] (with the time as argument)")},
       read_pressure},
      {"forces",
       "point_mass",
       "a mass at a point (a node, or a rigid body's point)",
       {pos("point", K::kPoint, "where"), pos("mass", K::kNonNegative, "[kg]")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const double m = r.non_negative("mass");
         const Point p = k.point(r.child("point"));
         k.at_entry(r, [&] { k.builder().point_mass(name, p, m); });
       }},
      {"forces",
       "torque",
       "the moment scale · T on a rigid body's angle: a constant or a time law",
       {pos("body", K::kName, "the rigid body"),
        opt_pos("torque", K::kNumber, "a constant moment [N m] (or law)"),
        kw("law", K::kLaw, "T(t) [N m]"), kw("scale", K::kNumber, "factor (default 1)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string body = r.string("body");
         if (r.has("torque") == r.has("law"))
           r.fail("expected either \"torque\": T or \"law\": {...} (one of them)");
         std::shared_ptr<const TimeLaw> l = r.has("torque")
                                                ? std::make_shared<ConstantLaw>(r.number("torque"))
                                                : k.law(r.child("law"));
         const double scale = r.number("scale", 1.0);
         k.at_entry(r, [&] { k.builder().torque(name, body, l, scale); });
       }},
      {"forces",
       "rotational_spring_damper",
       "a torsion spring and damper between the angles of two rigid bodies",
       {pos("a", K::kName, "a rigid body"),
        opt_pos("b", K::kName, "a rigid body, or \"ground\"", "\"ground\""),
        kw("stiffness", K::kNonNegative, "[N m/rad]", true),
        kw("damping", K::kNonNegative, "[N m s/rad] (default 0)"),
        kw("free_angle", K::kNumber, "[rad] (default: the initial relative angle)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string a = r.string("a"), b = r.string("b");
         RotationalSpringOptions o;
         o.stiffness = r.non_negative("stiffness");
         o.damping = r.non_negative("damping", 0.0);
         if (r.has("free_angle")) o.free_angle = r.number("free_angle");
         k.at_entry(r, [&] { k.builder().rotational_spring_damper(name, a, b, o); });
       }},
  };
}

// ---------------------------------------------------------------- measures
// A point of a rigid body, whose frame (origin there, the body's axes) a measure refers to.
PointRef frame_ref(KindReader& k, const JsonReader& r, const std::string& key) {
  const PointRef f = k.builder().resolve(k.point(r.child(key)));
  if (f.kind != PointRef::Kind::kBody)
    r.child(key).fail("body",
                      "expected a rigid body: the frame is a rigid body's (its axes, origin at "
                      "the point given)");
  return f;
}
PointRef point_ref(KindReader& k, const JsonReader& r, const std::string& key) {
  return k.builder().resolve(k.point(r.child(key)));
}
int angle_dof(KindReader& k, const JsonReader& r) {
  const std::string body = r.string("body");
  return k.at_key(r, "body", [&] { return k.builder().angle_dof(body); });
}
const FlexibleBody& flexible(KindReader& k, const JsonReader& r) {
  const std::string body = r.string("body");
  return k.at_key(r, "body", [&]() -> const FlexibleBody& { return k.builder().flexible(body); });
}

void read_distance(KindReader& k, const JsonReader& r, const std::string& name, bool elongation) {
  const PointRef a = point_ref(k, r, "a"), b = point_ref(k, r, "b");
  const double ref =
      elongation ? (k.builder().initial_position(b) - k.builder().initial_position(a)).norm() : 0.0;
  k.add_measure(std::make_unique<DistanceMeasure>(name, a, b, ref));
}

void read_path_deviation(KindReader& k, const JsonReader& r, const std::string& name) {
  const PointRef p = point_ref(k, r, "point");
  const JsonReader pr = r.child("path");
  pr.one_of("type", {"planar_chain"});
  ChainPath path;
  path.origin = pr.vec2("origin", Vec2::Zero());
  for (const auto& l : pr.items("links", true)) {
    const std::string d = l.string("driver");
    const DriverInfo* drv = k.builder().driver(d);
    if (!drv) l.fail("driver", "unknown driver '" + d + "'");
    path.links.push_back({drv->law, drv->relative, l.positive("length")});
    l.finish();
  }
  pr.finish();
  k.add_measure(std::make_unique<PathDeviationMeasure>(name, p, std::move(path)));
}

}  // namespace

std::vector<KindKey> stress_keys(const std::string& body_doc, bool body_positional) {
  KindKey body = kw("body", K::kName, body_doc, true);
  body.positional = body_positional;
  return {body, kw("reference", K::kPositive, "σ_ref of the KS aggregate [Pa] (required with ks)"),
          kw("aggregate", K::kName, "\"ks\" (default) or \"pnorm\""),
          kw("parameter", K::kPositive, "KS ρ (default 50) or p-norm p (default 8)"),
          kw("relaxation", K::kPositive, "q in (0, 1] (default 0.5)")};
}

StressMeasure::Options stress_options(const JsonReader& r) {
  StressMeasure::Options o;
  o.aggregation = r.one_of("aggregate", {"ks", "pnorm"}, "ks") == "ks"
                      ? StressMeasure::Aggregation::kKs
                      : StressMeasure::Aggregation::kPNorm;
  // σ_ref normalizes the KS exponent; a p-norm needs none
  o.reference = o.aggregation == StressMeasure::Aggregation::kKs ? r.positive("reference")
                                                                 : r.positive("reference", 1.0);
  o.parameter =
      r.positive("parameter", o.aggregation == StressMeasure::Aggregation::kKs ? 50.0 : 8.0);
  if (o.aggregation == StressMeasure::Aggregation::kPNorm && o.parameter < 1)
    r.fail("parameter", "expected a p-norm exponent >= 1");
  o.relaxation = r.positive("relaxation", 0.5);
  if (o.relaxation > 1) r.fail("relaxation", "expected the qp exponent q in (0, 1]");
  return o;
}

namespace {

void read_stress(KindReader& k, const JsonReader& r, const std::string& name) {
  const FlexibleBody& fb = flexible(k, r);
  k.add_measure(std::make_unique<StressMeasure>(name, &fb, stress_options(r)));
}

std::vector<ModelKind> point_measures() {
  const KindKey point = kw("point", K::kPoint, "the point measured", true);
  return {
      {"measures",
       "position",
       "x, y of a point (columns <name>.x, <name>.y) [m]",
       {point},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         k.add_measure(std::make_unique<PositionMeasure>(name, point_ref(k, r, "point")));
       }},
      {"measures",
       "velocity",
       "ẋ, ẏ of a point [m/s]",
       {point},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         k.add_measure(std::make_unique<VelocityMeasure>(name, point_ref(k, r, "point")));
       }},
      {"measures",
       "angle",
       "θ of a rigid body [rad]",
       {kw("body", K::kName, "the rigid body", true)},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         k.add_measure(std::make_unique<AngleMeasure>(name, angle_dof(k, r)));
       }},
      {"measures",
       "angular_velocity",
       "θ̇ of a rigid body [rad/s]",
       {kw("body", K::kName, "the rigid body", true)},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         k.add_measure(std::make_unique<AngularVelocityMeasure>(name, angle_dof(k, r)));
       }},
      {"measures",
       "distance",
       "|p_b − p_a| [m]",
       {kw("a", K::kPoint, "one point", true), kw("b", K::kPoint, "the other", true)},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         read_distance(k, r, name, false);
       }},
      {"measures",
       "elongation",
       "|p_b − p_a| minus its initial value [m] (eq. 42)",
       {kw("a", K::kPoint, "one point", true), kw("b", K::kPoint, "the other", true)},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         read_distance(k, r, name, true);
       }},
  };
}

std::vector<ModelKind> model_measures() {
  const KindKey point = kw("point", K::kPoint, "the point measured", true);
  return {
      {"measures",
       "path_deviation",
       "distance of a point from where a planar chain of driven links puts it (eq. 45) [m]",
       {kw("point", K::kPoint, "the point measured", true),
        kw("path", K::kJson,
           "{\"type\": \"planar_chain\", \"origin\": [x, y], \"links\": [{\"driver\": name, "
           "\"length\": m}, …]}",
           true)},
       read_path_deviation},
      {"measures",
       "constraint_force",
       "the multipliers λ of a joint's equations [N or N m]",
       {kw("joint", K::kName, "the joint", true)},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const std::string j = r.string("joint");
         k.at_key(r, "joint", [&] { return k.builder().joint_equations(j); });
         k.add_constraint_force(name, j);
       }},
      {"measures",
       "kinetic_energy",
       "of the whole model [J]",
       {},
       [](KindReader& k, const JsonReader&, const std::string& name) {
         k.add_measure(std::make_unique<KineticEnergyMeasure>(name));
       }},
      {"measures",
       "strain_energy",
       "of the flexible bodies [J]",
       {},
       [](KindReader& k, const JsonReader&, const std::string& name) {
         k.add_measure(std::make_unique<StrainEnergyMeasure>(name));
       }},
      {"measures",
       "mass",
       "of a flexible body at the design (eq. 3) [kg]",
       {kw("body", K::kName, "the flexible body", true)},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         k.add_measure(std::make_unique<FlexibleMassMeasure>(name, &flexible(k, r)));
       }},
      {"measures", "stress",
       "aggregated relaxed von Mises stress of a flexible body, s_e = μ_e^q σ_vM [Pa]",
       stress_keys("the flexible body", false), read_stress},
      {"measures",
       "frame_position",
       "a point's position in a rigid body's frame [m]",
       {point, kw("frame", K::kPoint, "a point of a rigid body: the frame's origin", true)},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         k.add_measure(std::make_unique<FramePositionMeasure>(name, point_ref(k, r, "point"),
                                                              frame_ref(k, r, "frame")));
       }},
      {"measures",
       "frame_velocity",
       "a point's velocity seen in a rigid body's frame [m/s]",
       {point, kw("frame", K::kPoint, "a point of a rigid body: the frame's origin", true)},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         k.add_measure(std::make_unique<FrameVelocityMeasure>(name, point_ref(k, r, "point"),
                                                              frame_ref(k, r, "frame")));
       }},
      {"measures",
       "line_distance",
       "signed distance of a point from the line through a and b [m]",
       {point, kw("a", K::kPoint, "a point of the line", true),
        kw("b", K::kPoint, "another point of the line", true)},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         const PointRef p = point_ref(k, r, "point"), a = point_ref(k, r, "a"),
                        b = point_ref(k, r, "b");
         if (!((k.builder().initial_position(b) - k.builder().initial_position(a)).norm() > 0))
           r.fail("b", "the line's two points coincide at t = 0 (a and b): no line through them");
         k.add_measure(std::make_unique<LineDistanceMeasure>(name, p, a, b));
       }},
      {"measures",
       "combination",
       "c0 + Σ w_i · (a column of an earlier measure)",
       {kw("terms", K::kJson, "[{\"measure\": column, \"weight\": w}, …]", true),
        kw("constant", K::kNumber, "c0 (default 0)")},
       [](KindReader& k, const JsonReader& r, const std::string& name) {
         k.add_measure(k.combination(r, name));
       }},
  };
}

// ---------------------------------------------------------------- features (design geometry)
// Their parameters are Feature::parameter_names(type), in that order (a test checks it); the
// design section of the loader reads them as numbers, variable names or {variable, scale, offset}.
std::vector<ModelKind> features() {
  const auto par = [](const char* n, const char* doc, std::string def = "") {
    return KindKey{n, K::kParameter, true, true, def, doc};
  };
  const KindKey hole =
      opt_pos("hole", K::kBoolean, "material outside (default true) or inside", "true");
  const KindKey non_design =
      kw("non_design", K::kBoolean, "solid inside and OR-ed with the region: material kept there");
  return {
      {"features",
       "ellipse",
       "((x − cx)/(a d))² + ((y − cy)/(b d))² = 1 turned by angle (eq. 41)",
       {par("cx", "centre x [m]"),
        par("cy", "centre y [m]"),
        par("a", "semi-axis [m]"),
        par("b", "semi-axis [m]"),
        par("d", "scale of both semi-axes (eq. 41)", "1.0"),
        {"angle", K::kParameter, false, true, "", "[rad] (default 0)"},
        hole,
        non_design},
       nullptr},
      {"features",
       "super_ellipse",
       "|u/a|^ξ + |v/b|^η = 1 in the frame turned by angle (eq. 43)",
       {par("cx", "centre x [m]"),
        par("cy", "centre y [m]"),
        par("a", "half-width [m]"),
        par("b", "half-height [m]"),
        par("xi", "exponent ξ", "5.0"),
        par("eta", "exponent η", "5.0"),
        {"angle", K::kParameter, false, true, "", "[rad] (default 0)"},
        hole,
        non_design},
       nullptr},
      {"features",
       "circle",
       "a circle of radius r",
       {par("cx", "centre x [m]"), par("cy", "centre y [m]"), par("r", "radius [m]"), hole,
        non_design},
       nullptr},
      {"features",
       "bspline",
       "a closed uniform cubic B-spline through its control points' hull; the exact signed "
       "distance to the curve",
       {{"control_points", K::kJson, true, true, "",
         "[[x, y], …] at least 4, in order; each coordinate a number, a variable name or "
         "{variable, scale, offset} [m]"},
        hole,
        non_design},
       nullptr},
  };
}

}  // namespace

const std::vector<ModelKind>& model_kinds() {
  static const std::vector<ModelKind> kinds = [] {
    std::vector<ModelKind> all;
    for (auto part : {joints(), forces(), point_measures(), model_measures(), features()})
      for (auto& k : part) all.push_back(std::move(k));
    return all;
  }();
  return kinds;
}

const ModelKind* find_kind_in(const std::vector<ModelKind>& kinds, const std::string& section,
                              const std::string& type) {
  for (const auto& k : kinds)
    if (k.section == section && k.type == type) return &k;
  return nullptr;
}

std::vector<std::string> kind_types_in(const std::vector<ModelKind>& kinds,
                                       const std::string& section) {
  std::vector<std::string> v;
  for (const auto& k : kinds)
    if (k.section == section) v.push_back(k.type);
  return v;
}

const ModelKind* find_kind(const std::string& section, const std::string& type) {
  return find_kind_in(model_kinds(), section, type);
}

std::vector<std::string> kind_types(const std::string& section) {
  return kind_types_in(model_kinds(), section);
}

}  // namespace lsmbs
