#include <Eigen/OrderingMethods>
#include <Eigen/SparseQR>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "lsmbs/core/file_check.hpp"
#include "lsmbs/integrators/initial_state.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/json_reader.hpp"
#include "lsmbs/io/sha256.hpp"

namespace lsmbs {

Error locate(const std::string& case_file, const SetupError& e) {
  // subjects are dotted names of the case's sections; responses and measures sit under /output
  std::string path = "/" + e.subject();
  for (auto& ch : path)
    if (ch == '.') ch = '/';
  if (path.rfind("/responses", 0) == 0 || path.rfind("/measures", 0) == 0) path = "/output" + path;
  return Error(case_file, path, e.reason());
}

namespace {

namespace fs = std::filesystem;

std::string format_g(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

struct Loader {
  Loader(Case& c, std::string dir) : cs(c), base_dir(std::move(dir)) {}
  Case& cs;
  std::string base_dir;
  Model& model() { return *cs.model; }
  std::set<std::string> names;  // bodies, joints, forces share one namespace

  std::string resolve(const std::string& f) const {
    return fs::path(f).is_absolute() ? f : (fs::path(base_dir) / f).string();
  }

  void unique_name(const JsonReader& r, const std::string& name) {
    if (!names.insert(name).second) r.fail("name", "duplicate name '" + name + "' (bodies, joints and forces need unique names)");
  }

  int param(const std::string& name, double value) { return model().add_parameter(name, value); }

  // ---------------------------------------------------------------- time laws
  std::shared_ptr<const TimeLaw> law(const JsonReader& r) {
    const std::string type = r.one_of("type", {"trapezoid", "ramp", "table", "constant"});
    std::shared_ptr<const TimeLaw> out;
    try {
      if (type == "trapezoid") {
        out = std::make_shared<TrapezoidLaw>(r.number("from"), r.number("to"), r.positive("acceleration"),
                                             r.positive("speed"), r.number("start", 0.0));
      } else if (type == "ramp") {
        out = std::make_shared<RampLaw>(r.number("from", 0.0), r.number("speed"), r.positive("ramp_time"),
                                        r.number("start", 0.0));
      } else if (type == "constant") {
        out = std::make_shared<ConstantLaw>(r.number("value"));
      } else {
        out = std::make_shared<TabulatedLaw>(table(r));
      }
    } catch (const Error& e) {
      if (!e.json_path().empty()) throw;
      r.fail(e.what());
    }
    r.finish();
    return out;
  }

  Table1D table(const JsonReader& r) {
    const auto interp = r.one_of("interpolation", {"cubic", "linear"}, "cubic") == "cubic" ? Table1D::Interp::kCubic
                                                                                         : Table1D::Interp::kLinear;
    const double period = r.non_negative("period", 0.0);
    // x_scale multiplies the abscissae (which must increase): a positive factor; y_scale any factor
    const double xs = r.positive("x_scale", 1.0), ys = r.number("y_scale", 1.0);
    if (r.has("file") && r.has("points")) r.fail("expected either \"file\" or \"points\", not both");
    if (r.has("file")) {
      const std::string f = resolve(r.string("file"));
      try {
        return Table1D::read_csv(f, interp, period, xs, ys);
      } catch (const Error& e) {  // name the case's JSON path too (the message names the table file)
        r.fail("file", e.what());
      }
    }
    std::vector<double> x, y;
    for (const auto& p : r.items("points", true)) {
      if (!p.is_array() || p.size() != 2) p.fail("expected a pair [x, y]");
      x.push_back(p.at(0).as_number() * xs);
      y.push_back(p.at(1).as_number() * ys);
    }
    try {
      return Table1D(x, y, interp, period);
    } catch (const Error& e) {
      r.fail("points", e.what());
    }
  }

  // ---------------------------------------------------------------- points
  PointRef point(const JsonReader& r) {
    PointRef p;
    if (r.is_string()) {
      if (r.as_string() == "ground") r.fail("a ground point needs coordinates: {\"ground\": [x, y]}");
      r.fail("expected a point object ({\"ground\": [x, y]}, {\"body\": name, \"at\": [x, y]}, {\"body\": name, \"node\": i})");
    }
    if (!r.is_object()) r.fail("expected a point object");
    if (r.has("ground")) {
      p.kind = PointRef::Kind::kGround;
      p.local = r.vec2("ground");
      r.finish();
      return p;
    }
    const std::string body = r.string("body");
    if (const RigidBody* rb = model().find_rigid(body)) {
      p.kind = PointRef::Kind::kBody;
      p.dof0 = rb->dof0;
      if (r.has("at_global")) p.local = rotation(rb->angle0).transpose() * (r.vec2("at_global") - rb->position0);
      else p.local = r.vec2("at", Vec2::Zero());
    } else if (const FlexibleBody* fb = model().find_flexible(body)) {
      p.kind = PointRef::Kind::kNode;
      int node = -1;
      if (r.has("node")) {
        node = r.integer("node", 0);
        if (node >= fb->mesh.num_nodes())
          r.fail("node", "node index " + std::to_string(node) + " out of range (body '" + body + "' has " +
                             std::to_string(fb->mesh.num_nodes()) + " nodes)");
      } else if (r.has("nearest")) {
        node = fb->mesh.nearest_node(r.vec2("nearest"));
      } else {
        r.fail("a point on a flexible body needs \"node\": index or \"nearest\": [x, y] (mesh frame)");
      }
      p.dof0 = fb->node_dof(node);
    } else {
      r.fail("body", "unknown body '" + body + "'");
    }
    r.finish();
    return p;
  }

  Vec2 initial_position(const PointRef& p) const {
    if (p.kind == PointRef::Kind::kGround) return p.local;
    const Vec q = cs.model->initial_positions();
    double b[3] = {q[p.dof0], q[p.dof0 + 1], p.kind == PointRef::Kind::kBody ? q[p.dof0 + 2] : 0};
    return PointKinematics::position(p, b);
  }

  const RigidBody& rigid(const JsonReader& r, const std::string& key) {
    const std::string n = r.string(key);
    const RigidBody* b = model().find_rigid(n);
    if (!b) {
      if (model().find_flexible(n)) r.fail(key, "'" + n + "' is a flexible body; a rigid body is expected here");
      r.fail(key, "unknown rigid body '" + n + "'");
    }
    return *b;
  }

  const FlexibleBody& flexible(const JsonReader& r, const std::string& key) {
    const std::string n = r.string(key);
    const FlexibleBody* b = model().find_flexible(n);
    if (!b) r.fail(key, "unknown flexible body '" + n + "'");
    return *b;
  }

  std::vector<int> node_set(const JsonReader& r, const std::string& key, const FlexibleBody& b) {
    const std::string n = r.string(key);
    auto it = b.mesh.node_sets.find(n);
    if (it == b.mesh.node_sets.end()) {
      std::string avail;
      for (const auto& [k, v] : b.mesh.node_sets) avail += (avail.empty() ? "" : ", ") + k;
      r.fail(key, "body '" + b.name + "' has no node set '" + n + "' (available: " + avail + ")");
    }
    return it->second;
  }

  // ---------------------------------------------------------------- bodies
  void rigid_body(const JsonReader& r, const std::string& name) {
    RigidBody b;
    b.name = name;
    b.position0 = r.vec2("position", Vec2::Zero());
    b.angle0 = r.number("angle", 0.0);
    b.com_offset = r.vec2("com", Vec2::Zero());
    b.mass_param = param(name + ".mass", r.non_negative("mass", 0.0));
    b.inertia_param = param(name + ".inertia", r.non_negative("inertia", 0.0));
    const Vec2 v0 = r.vec2("velocity", Vec2::Zero());
    const double w0 = r.number("angular_velocity", 0.0);
    r.finish();
    const RigidBody& rb = model().add_rigid_body(b);
    model().add_force(std::make_unique<RigidInertia>(rb.dof0, rb.mass_param, rb.inertia_param, rb.com_offset,
                                                     "rigid body '" + name + "'"));
    init_v.conservativeResize(model().nq());
    init_v.segment<3>(rb.dof0) << v0.x(), v0.y(), w0;
    given_velocity(r, rb.dof0, rb.dof0 + 2, r.has("velocity"), r.has("angular_velocity"));
  }

  void flexible_body(const JsonReader& r, const std::string& name) {
    FlexibleBody b;
    b.name = name;
    const JsonReader m = r.child("mesh");
    const std::string mt = m.one_of("type", {"rectangle", "gmsh"});
    if (mt == "rectangle") {
      const Vec2 o = m.vec2("origin", Vec2::Zero()), sz = m.vec2("size");
      if (!(sz.x() > 0 && sz.y() > 0)) m.fail("size", "expected positive lengths");
      const JsonReader el = m.child("elements");
      if (!el.is_array() || el.size() != 2) el.fail("expected [nx, ny]");
      const double nx = el.at(0).as_number(), ny = el.at(1).as_number();
      if (nx < 1 || ny < 1 || nx != std::floor(nx) || ny != std::floor(ny) || nx * ny > 5e6)
        el.fail("expected two positive integers [nx, ny]");
      b.mesh = Mesh2D::rectangle(o.x(), o.y(), sz.x(), sz.y(), static_cast<int>(nx), static_cast<int>(ny));
    } else {
      const std::string f = resolve(m.string("file"));
      try {
        b.mesh = Mesh2D::read_gmsh(f);
      } catch (const Error& e) {
        throw Error(std::string(e.what()) + " (referenced from " + cs.file + ": " + m.path() + "/file)");
      }
      const double sc = m.positive("scale", 1.0);
      for (auto& x : b.mesh.nodes) {
        x *= sc;
        if (!x.allFinite() || x.norm() > 1e100)  // lengths beyond 1e100 m overflow in the element integrals
          m.fail("scale", "the scaled mesh coordinates are out of range (scale " + format_g(sc) + ")");
      }
    }
    m.finish();
    if (auto pl = r.optional_child("placement")) {
      b.origin = pl->vec2("origin", Vec2::Zero());
      b.angle = pl->number("angle", 0.0);
      pl->finish();
    }
    const JsonReader mat = r.child("material");
    b.E_param = param(name + ".E", mat.positive("E"));
    const double nu = mat.number("nu");
    if (!(nu >= 0 && nu < 0.5)) mat.fail("nu", "expected Poisson's ratio in [0, 0.5)");
    b.nu_param = param(name + ".nu", nu);
    b.rho_param = param(name + ".rho", mat.positive("rho"));
    mat.finish();
    b.thickness_param = param(name + ".thickness", r.positive("thickness"));
    b.integration = r.one_of("integration", {"selective-shear", "full"}, "selective-shear") == "full"
                        ? QuadIntegration::kFull
                        : QuadIntegration::kSelectiveShear;
    // Node sets by selector (mesh frame).
    if (auto ns = r.optional_child("node_sets")) {
      if (!ns->is_object()) ns->fail("expected an object {name: selector}");
      for (const auto& key : ns->keys()) {
        const JsonReader s = ns->child(key);
        const double tol = s.has("tolerance") ? s.positive("tolerance") : -1.0;  // -1: the mesh's default
        std::vector<int> sel;
        if (s.has("line_x")) sel = b.mesh.nodes_on_line_x(s.number("line_x"), tol);
        else if (s.has("line_y")) sel = b.mesh.nodes_on_line_y(s.number("line_y"), tol);
        else if (s.has("circle")) {
          const JsonReader c = s.child("circle");
          sel = b.mesh.nodes_on_circle(c.vec2("center"), c.positive("radius"), tol);
          c.finish();
        } else if (s.has("box")) {
          const JsonReader c = s.child("box");
          sel = b.mesh.nodes_in_box(c.vec2("min"), c.vec2("max"));
          c.finish();
        } else if (s.has("nodes")) {
          for (const auto& it : s.items("nodes")) {
            const double v = it.as_number();
            if (v < 0 || v >= b.mesh.num_nodes() || v != std::floor(v)) it.fail("expected a node index of the mesh");
            sel.push_back(static_cast<int>(v));
          }
        } else {
          s.fail("expected a selector: line_x, line_y, circle, box or nodes");
        }
        s.finish();
        if (sel.empty()) s.fail("the selector selects no node of body '" + name + "'");
        b.mesh.node_sets[key] = sel;
      }
    }
    const Vec2 v0 = r.vec2("velocity", Vec2::Zero());
    const double w0 = r.number("angular_velocity", 0.0);
    r.finish();
    const FlexibleBody* added = nullptr;
    try {  // the element geometry is checked here (inverted or degenerate quadrilaterals)
      added = &model().add_flexible_body(std::move(b));
    } catch (const Error& e) {
      r.fail("mesh", std::string(e.what()) + " (check the mesh's coordinates: origin, size, scale)");
    }
    const FlexibleBody& fb = *added;
    init_v.conservativeResize(model().nq());
    for (int i = 0; i < fb.mesh.num_nodes(); ++i) {
      const Vec2 x = fb.placed(i) - fb.origin;
      init_v.segment<2>(fb.node_dof(i)) = v0 + w0 * Vec2(-x.y(), x.x());
    }
    const bool given = r.has("velocity") || r.has("angular_velocity");  // the whole rigid field
    given_velocity(r, fb.node_dof(0), model().nq(), given, given);
  }

  // ---------------------------------------------------------------- joints and drivers
  void joint(const JsonReader& r, int index) {
    const std::string type =
        r.one_of("type", {"revolute", "prismatic", "rigid_connection", "clamp", "rotation_driver", "translation_driver"});
    const std::string name = r.string("name", type + "_" + std::to_string(index));
    unique_name(r, name);
    joint_paths[name] = r.path();
    const size_t first = model().constraints().size();
    auto add = [&](std::unique_ptr<ConstraintElement> c) {
      c->set_name(name);
      model().add_constraint(std::move(c));
    };
    if (type == "revolute") {
      const PointRef a = point(r.child("a"));
      PointRef b;
      if (r.has("b")) {
        const JsonReader rb = r.child("b");
        if (rb.is_string() && rb.as_string() == "ground") b = {PointRef::Kind::kGround, -1, initial_position(a)};
        else b = point(rb);
      } else {
        b = {PointRef::Kind::kGround, -1, initial_position(a)};
      }
      if (a.kind == PointRef::Kind::kGround && b.kind == PointRef::Kind::kGround) r.fail("both points are ground");
      add(std::make_unique<PointCoincidence>(a, b));
    } else if (type == "prismatic") {
      const PointRef a = point(r.child("a"));
      if (a.kind == PointRef::Kind::kGround) r.fail("a", "the sliding point must be on a body");
      const Vec2 u = r.vec2("direction");
      if (!(u.norm() > 0)) r.fail("direction", "expected a non-zero direction");
      const Vec2 x0 = r.vec2("through", initial_position(a));
      const bool lock = r.boolean("lock_rotation", true);
      double th0 = 0;
      if (a.kind == PointRef::Kind::kBody) th0 = model().initial_positions()[a.dof0 + 2];
      add(std::make_unique<Prismatic>(a, x0, u, lock, th0));
    } else if (type == "rigid_connection") {
      const RigidBody& rb = rigid(r, "rigid");
      const FlexibleBody& fb = flexible(r, "flexible");
      const auto nodes = node_set(r, "node_set", fb);
      for (int nd : nodes) {
        const Vec2 off = rotation(rb.angle0).transpose() * (fb.placed(nd) - rb.position0);
        add(std::make_unique<PointCoincidence>(PointRef{PointRef::Kind::kNode, fb.node_dof(nd), Vec2::Zero()},
                                               PointRef{PointRef::Kind::kBody, rb.dof0, off}));
      }
    } else if (type == "clamp") {
      const FlexibleBody& fb = flexible(r, "flexible");
      for (int nd : node_set(r, "node_set", fb))
        add(std::make_unique<PointCoincidence>(PointRef{PointRef::Kind::kNode, fb.node_dof(nd), Vec2::Zero()},
                                               PointRef{PointRef::Kind::kGround, -1, fb.placed(nd)}));
    } else if (type == "rotation_driver") {
      const RigidBody& b = rigid(r, "body");
      int a_dof = -1;
      const std::string rel = r.string("relative_to", "ground");
      if (rel != "ground") {
        const RigidBody* a = model().find_rigid(rel);
        if (!a) r.fail("relative_to", "unknown rigid body '" + rel + "' (or \"ground\")");
        if (a == &b) r.fail("relative_to", "a body cannot be driven relative to itself");
        a_dof = a->dof0 + 2;
      }
      auto l = law(r.child("law"));
      cs.drivers[name] = l;
      driver_relative[name] = a_dof >= 0;
      add(std::make_unique<AngleDriver>(a_dof, b.dof0 + 2, l));
    } else {  // translation_driver
      const PointRef a = point(r.child("point"));
      const Vec2 u = r.vec2("direction");
      if (!(u.norm() > 0)) r.fail("direction", "expected a non-zero direction");
      const Vec2 x0 = r.vec2("through", initial_position(a));
      auto l = law(r.child("law"));
      cs.drivers[name] = l;
      driver_relative[name] = false;
      add(std::make_unique<TranslationDriver>(a, x0, u, l));
    }
    r.finish();
    // rows are numbered at finalize(); remember the element range of this joint
    joint_elements[name] = {first, model().constraints().size()};
  }

  // ---------------------------------------------------------------- forces
  void force(const JsonReader& r, int index) {
    const std::string type = r.one_of(
        "type", {"point_force", "spring_damper", "pressure", "point_mass", "torque", "rotational_spring_damper"});
    const std::string name = r.string("name", type + "_" + std::to_string(index));
    unique_name(r, name);
    begin_entry(r, name);
    if (type == "point_mass") {
      const double m = r.non_negative("mass");
      const PointRef p = point(r.child("point"));
      if (p.kind == PointRef::Kind::kGround) r.fail("point", "a point mass must sit on a body");
      const int mp = param(name + ".mass", m);
      if (p.kind == PointRef::Kind::kNode) model().add_force(std::make_unique<NodeMass>(p.dof0, mp, "point mass '" + name + "'"));
      else model().add_force(std::make_unique<RigidInertia>(p.dof0, mp, -1, p.local, "point mass '" + name + "'"));
    } else if (type == "point_force") {
      const PointRef p = point(r.child("point"));
      if (p.kind == PointRef::Kind::kGround) r.fail("point", "a force must act on a body");
      std::shared_ptr<const TimeLaw> fx, fy;
      if (r.has("force")) {
        const Vec2 f = r.vec2("force");
        fx = std::make_shared<ConstantLaw>(f.x());
        fy = std::make_shared<ConstantLaw>(f.y());
      } else {
        fx = r.has("fx") ? law(r.child("fx")) : std::make_shared<ConstantLaw>(0.0);
        fy = r.has("fy") ? law(r.child("fy")) : std::make_shared<ConstantLaw>(0.0);
      }
      const int sp = param(name + ".scale", r.number("scale", 1.0));
      model().add_force(std::make_unique<PointForce>(p, fx, fy, sp, "force '" + name + "'"));
    } else if (type == "spring_damper") {
      const PointRef a = point(r.child("a")), b = point(r.child("b"));
      const double l_init = (initial_position(b) - initial_position(a)).norm();
      const int kp = param(name + ".stiffness", r.non_negative("stiffness"));
      const int cp = param(name + ".damping", r.non_negative("damping", 0.0));
      const int lp = param(name + ".free_length", r.non_negative("free_length", l_init));
      if (!(l_init > 0)) r.fail("the spring's end points coincide initially (direction undefined)");
      model().add_force(std::make_unique<SpringDamper>(a, b, kp, cp, lp, "spring '" + name + "'"));
    } else if (type == "torque") {
      const RigidBody& b = rigid(r, "body");
      if (r.has("torque") == r.has("law")) r.fail("expected either \"torque\": T or \"law\": {...} (one of them)");
      std::shared_ptr<const TimeLaw> l =
          r.has("torque") ? std::make_shared<ConstantLaw>(r.number("torque")) : law(r.child("law"));
      const int sp = param(name + ".scale", r.number("scale", 1.0));
      model().add_force(std::make_unique<Torque>(b.dof0 + 2, l, sp, "torque '" + name + "'"));
    } else if (type == "rotational_spring_damper") {
      const RigidBody& a = rigid(r, "a");
      int b_dof = -1;
      double th_b = 0;
      const std::string bn = r.string("b");
      if (bn != "ground") {
        const RigidBody& b = rigid(r, "b");
        if (&b == &a) r.fail("b", "a rotational spring cannot connect a body to itself");
        b_dof = b.dof0 + 2;
        th_b = b.angle0;
      }
      const int kp = param(name + ".stiffness", r.non_negative("stiffness"));
      const int cp = param(name + ".damping", r.non_negative("damping", 0.0));
      const int tp = param(name + ".free_angle", r.number("free_angle", a.angle0 - th_b));
      model().add_force(
          std::make_unique<RotationalSpringDamper>(a.dof0 + 2, b_dof, kp, cp, tp, "rotational spring '" + name + "'"));
    } else {  // pressure
      const PointRef p = point(r.child("point"));
      if (p.kind == PointRef::Kind::kGround) r.fail("point", "a pressure force must act on a body");
      const Vec2 u = r.vec2("direction");
      if (!(u.norm() > 0)) r.fail("direction", "expected a non-zero direction");
      const int ap = param(name + ".area", r.positive("area"));
      const JsonReader tr = r.child("table");
      Table1D t = table(tr);
      tr.finish();  // a misspelt table option (e.g. "x_scal") is an error, not ignored
      int angle_dof = -1;
      double offset = 0;
      if (r.has("argument")) {
        const JsonReader a = r.child("argument");
        if (a.is_string()) {
          if (a.as_string() != "time") a.fail("expected \"time\" or {\"angle_of\": body, \"offset\": rad}");
        } else {
          angle_dof = rigid(a, "angle_of").dof0 + 2;
          offset = a.number("offset", 0.0);
          a.finish();
        }
      }
      if (angle_dof < 0) offset = r.number("time_offset", 0.0);
      model().add_force(std::make_unique<PressureForce>(p, u, ap, std::move(t), angle_dof, offset, "pressure '" + name + "'"));
    }
    r.finish();
  }

  // ---------------------------------------------------------------- measures and responses
  void measure(const JsonReader& r) {
    const std::string type =
        r.one_of("type", {"position", "velocity", "angle", "angular_velocity", "distance", "elongation", "path_deviation",
                          "constraint_force", "kinetic_energy", "strain_energy", "mass"});
    const std::string name = r.string("name");
    // constraint_force measures are placeholders (null) until finalize: their names are pending
    for (const auto& m : cs.measures)
      if (m && m->name() == name) r.fail("name", "duplicate measure name '" + name + "'");
    for (const auto& pending : pending_forces)
      if (pending.first == name) r.fail("name", "duplicate measure name '" + name + "'");
    std::unique_ptr<Measure> m;
    if (type == "position") m = std::make_unique<PositionMeasure>(name, point(r.child("point")));
    else if (type == "velocity") m = std::make_unique<VelocityMeasure>(name, point(r.child("point")));
    else if (type == "angle") m = std::make_unique<AngleMeasure>(name, rigid(r, "body").dof0 + 2);
    else if (type == "angular_velocity") m = std::make_unique<AngularVelocityMeasure>(name, rigid(r, "body").dof0 + 2);
    else if (type == "distance" || type == "elongation") {
      const PointRef a = point(r.child("a")), b = point(r.child("b"));
      const double ref = type == "elongation" ? (initial_position(b) - initial_position(a)).norm() : 0.0;
      m = std::make_unique<DistanceMeasure>(name, a, b, ref);
    } else if (type == "path_deviation") {
      const PointRef p = point(r.child("point"));
      const JsonReader pr = r.child("path");
      pr.one_of("type", {"planar_chain"});
      ChainPath path;
      path.origin = pr.vec2("origin", Vec2::Zero());
      for (const auto& l : pr.items("links", true)) {
        const std::string d = l.string("driver");
        if (!cs.drivers.count(d)) l.fail("driver", "unknown driver '" + d + "'");
        path.links.push_back({cs.drivers[d], driver_relative[d], l.positive("length")});
        l.finish();
      }
      pr.finish();
      m = std::make_unique<PathDeviationMeasure>(name, p, std::move(path));
    } else if (type == "constraint_force") {
      const std::string j = r.string("joint");
      if (!joint_elements.count(j)) r.fail("joint", "unknown joint '" + j + "'");
      pending_forces.emplace_back(name, j);
      r.finish();
      cs.measures.push_back(nullptr);  // filled after finalize (rows known then)
      return;
    } else if (type == "kinetic_energy") m = std::make_unique<KineticEnergyMeasure>(name);
    else if (type == "strain_energy") m = std::make_unique<StrainEnergyMeasure>(name);
    else m = std::make_unique<FlexibleMassMeasure>(name, &flexible(r, "body"));
    r.finish();
    cs.measures.push_back(std::move(m));
  }

  void response(const JsonReader& r) {
    ResponseSpec s;
    s.name = r.string("name");
    const std::string meas = r.string("measure");
    int col = -1;
    const auto cols = column_names();
    for (size_t i = 0; i < cols.size(); ++i)
      if (cols[i] == meas) col = static_cast<int>(i);
    if (col < 0) r.fail("measure", "unknown measure column '" + meas + "'");
    s.column = col;
    const std::string agg =
        r.one_of("aggregate", {"average", "average_eq45", "max", "min", "final", "integral", "rms", "per_step", "ks"});
    using K = ResponseSpec::Kind;
    s.kind = agg == "average" ? K::kAverage : agg == "average_eq45" ? K::kAverageEq45 : agg == "max" ? K::kMax
           : agg == "min" ? K::kMin : agg == "final" ? K::kFinal : agg == "integral" ? K::kIntegral
           : agg == "rms" ? K::kRms : agg == "per_step" ? K::kPerStep : K::kKS;
    if (s.kind == K::kKS) s.ks = r.positive("ks");
    if (auto w = r.optional_child("window")) {
      if (w->has("phase")) {
        const std::string d = w->string("driver");
        if (!cs.drivers.count(d)) w->fail("driver", "unknown driver '" + d + "'");
        const std::string ph = w->string("phase");
        bool found = false;
        std::string avail;
        for (const auto& p : cs.drivers[d]->phases()) {
          avail += (avail.empty() ? "" : ", ") + p.name;
          if (p.name == ph) {
            s.t0 = p.t0, s.t1 = p.t1, found = true;
          }
        }
        if (!found) w->fail("phase", "driver '" + d + "' has no phase '" + ph + "' (phases: " + (avail.empty() ? "none" : avail) + ")");
        s.window_text = "phase '" + ph + "' of driver '" + d + "'";
      } else {
        s.t0 = w->number("t0", -1e300);
        s.t1 = w->number("t1", 1e300);
        if (s.t1 < s.t0) w->fail("t1", "expected t1 >= t0");
        s.window_text = "[" + std::to_string(s.t0) + ", " + std::to_string(s.t1) + "] s";
      }
      w->finish();
    } else {
      s.window_text = "whole run";
    }
    r.finish();
    for (const auto& o : cs.responses)
      if (o.name == s.name) r.fail("name", "duplicate response name '" + s.name + "'");
    cs.responses.push_back(s);
  }

  std::vector<std::string> column_names() const {
    std::vector<std::string> c;
    for (size_t i = 0; i < cs.measures.size(); ++i) {
      if (cs.measures[i]) {
        for (auto& s : cs.measures[i]->components()) c.push_back(s);
      } else {  // constraint-force measure (built after finalize): components from the joint's equations
        const auto& [nm, j] = pending_forces[pending_index(i)];
        const auto [b, e] = joint_elements.at(j);
        int m = 0;
        for (size_t k = b; k < e; ++k) m += cs.model->constraints()[k]->size();
        for (int k = 0; k < m; ++k) c.push_back(nm + "." + std::to_string(k));
      }
    }
    return c;
  }
  size_t pending_index(size_t measure_index) const {
    size_t n = 0;
    for (size_t i = 0; i < measure_index; ++i)
      if (!cs.measures[i]) ++n;
    return n;
  }

  // ---------------------------------------------------------------- simulation options
  void simulation(const JsonReader& r) {
    auto& o = cs.simulation;
    o.t_end = r.positive("t_end");
    o.h = r.positive("h");
    o.rho_inf = r.number("rho_inf", o.rho_inf);
    o.tol_r = r.positive("tol_r", o.tol_r);
    o.tol_phi = r.positive("tol_phi", o.tol_phi);
    o.tol_q = r.positive("tol_q", o.tol_q);
    o.max_iter = r.integer("max_iter", o.max_iter, 1);
    o.min_iter = r.integer("min_iter", o.min_iter, 0);
    o.max_halvings = r.integer("max_halvings", o.max_halvings, 0);
    o.consistent_start = r.boolean("consistent_start", o.consistent_start);
    o.project_initial = r.boolean("project_initial", o.project_initial);
    {
      const std::string nw = r.one_of("newton", {"full", "modified", "modified_across_steps"}, "full");
      using N = GeneralizedAlphaOptions::Newton;
      o.newton = nw == "full" ? N::kFull : nw == "modified" ? N::kModified : N::kModifiedAcrossSteps;
    }
    cs.check_constraints = r.boolean("check_constraints", true);
    o.ordering = r.one_of("ordering", {"amd", "nested_dissection"}, "amd") == "amd"
                     ? SparseLU::Ordering::kAmd
                     : SparseLU::Ordering::kNestedDissection;
    o.k = r.non_negative("k", 0.0);
    o.zeta = r.non_negative("zeta", 0.0);
    if (auto msg = o.validate(); !msg.empty()) {
      const auto colon = msg.find(':');
      r.fail(msg.substr(0, colon), msg.substr(colon + 2));
    }
    if (o.t_end / o.h > 1e8) r.fail("h", "more than 1e8 steps requested");
    if (o.h > o.t_end * (1 + 1e-9))  // zero steps: the run would end at t = 0 and report it complete
      r.fail("h", "h = " + format_g(o.h) + " is longer than t_end = " + format_g(o.t_end) + " (the run would have no step)");
    {  // the output grid must end on t_end: no silent overshoot (the run starts at t = 0)
      const double n = o.t_end / o.h;
      if (std::abs(n - std::round(n)) > 1e-9 * std::max(1.0, n)) {
        char msg[256];
        std::snprintf(msg, sizeof msg,
                      "t_end = %.10g is not a multiple of h = %.10g (%.6g steps): the run would end after t_end; "
                      "use h = %.10g (%ld steps) or t_end = %.10g",
                      o.t_end, o.h, n, o.t_end / std::ceil(n), static_cast<long>(std::ceil(n)), std::ceil(n) * o.h);
        r.fail("h", msg);
      }
    }
    r.finish();
  }

  // ---------------------------------------------------------------- design
  ParamBinding binding(const JsonReader& r, const std::string& key, const Design& d) {
    ParamBinding b;
    const JsonReader v = r.child(key);
    auto var = [&](const JsonReader& at, const std::string& name) {
      const int k = d.variable_index(name);
      if (k < 0) at.fail("unknown design variable '" + name + "'");
      return k;
    };
    if (v.raw().is_number()) {
      b.offset = v.as_number();
    } else if (v.is_string()) {
      b.variable = var(v, v.as_string());
      b.scale = 1;
    } else if (v.is_object()) {
      b.variable = var(v, v.string("variable"));
      b.scale = v.number("scale", 1.0);
      b.offset = v.number("offset", 0.0);
      v.finish();
    } else {
      v.fail("expected a number, a design variable name, or {\"variable\", \"scale\", \"offset\"}");
    }
    return b;
  }

  LevelSetNode region(const JsonReader& r, const std::map<std::string, int>& features) {
    LevelSetNode n;
    if (r.is_string()) {
      auto it = features.find(r.as_string());
      if (it == features.end()) r.fail("unknown feature '" + r.as_string() + "'");
      n.op = LevelSetNode::Op::kFeature;
      n.feature = it->second;
      return n;
    }
    if (!r.is_object()) r.fail("expected a feature name or {\"and\" | \"or\": [...]} or {\"not\": ...}");
    if (r.has("not")) {
      n.op = LevelSetNode::Op::kNot;
      n.children.push_back(region(r.child("not"), features));
    } else {
      const bool is_and = r.has("and");
      if (!is_and && !r.has("or")) r.fail("expected \"and\", \"or\" or \"not\"");
      n.op = is_and ? LevelSetNode::Op::kAnd : LevelSetNode::Op::kOr;
      const auto items = r.items(is_and ? "and" : "or", true);
      if (items.empty()) r.fail(is_and ? "and" : "or", "expected at least one operand");
      for (const auto& c : items) n.children.push_back(region(c, features));
      n.ks = r.non_negative("ks", 0.0);
    }
    r.finish();
    return n;
  }

  void design(const JsonReader& r) {
    auto d = std::make_unique<Design>();
    for (const auto& v : r.items("variables", true)) {
      DesignVariable dv;
      dv.name = v.string("name");
      if (d->variable_index(dv.name) >= 0) v.fail("name", "duplicate design variable '" + dv.name + "'");
      dv.lower = v.number("lower");
      dv.upper = v.number("upper");
      dv.initial = v.number("initial");
      if (!(dv.upper > dv.lower)) v.fail("upper", "expected upper > lower");
      if (dv.initial < dv.lower || dv.initial > dv.upper)
        v.fail("initial", "initial value " + std::to_string(dv.initial) + " is outside its bounds [" +
                              std::to_string(dv.lower) + ", " + std::to_string(dv.upper) + "]");
      v.finish();
      d->variables.push_back(dv);
    }
    if (d->variables.empty()) r.fail("variables", "expected at least one design variable");
    for (const auto& g : r.items("geometry")) {
      const FlexibleBody& fb = flexible(g, "body");
      for (const auto& other : d->bodies)
        if (other.body == &fb) g.fail("body", "body '" + fb.name + "' has two geometry entries");
      std::vector<Feature> feats;
      std::map<std::string, int> by_name;
      for (const auto& f : g.items("features", true)) {
        const std::string name = f.string("name");
        if (by_name.count(name)) f.fail("name", "duplicate feature name '" + name + "'");
        bool ok = false;
        const std::string ts = f.one_of("type", {"ellipse", "super_ellipse", "circle"});
        const auto type = Feature::parse_type(ts, &ok);
        std::vector<ParamBinding> ps;
        for (const auto& pn : Feature::parameter_names(type)) {
          if (pn == "angle" && !f.has("angle")) ps.push_back(ParamBinding{});
          else ps.push_back(binding(f, pn, *d));
        }
        const bool hole = f.boolean("hole", true);
        f.finish();
        Feature feat(name, type, ps, hole);
        // each parameter is monotone in its variable: its extremes are at the bounds
        std::vector<double> lo, hi;
        for (const auto& b : ps) {
          const double a = b.variable < 0 ? b.offset : b.offset + b.scale * d->variables[b.variable].lower;
          const double c = b.variable < 0 ? b.offset : b.offset + b.scale * d->variables[b.variable].upper;
          lo.push_back(std::min(a, c));
          hi.push_back(std::max(a, c));
        }
        for (const auto* th : {&lo, &hi})
          if (auto msg = feat.check(*th); !msg.empty())
            f.fail("feature '" + name + "' is degenerate within the design bounds: " + msg);
        by_name[name] = static_cast<int>(feats.size());
        feats.push_back(std::move(feat));
      }
      LevelSetNode root;
      if (g.has("region")) {
        root = region(g.child("region"), by_name);
      } else {  // the paper's default: material where every hole feature is positive
        root.op = LevelSetNode::Op::kAnd;
        for (size_t i = 0; i < feats.size(); ++i) {
          LevelSetNode leaf;
          leaf.feature = static_cast<int>(i);
          root.children.push_back(leaf);
        }
      }
      MappingOptions mo;
      mo.mu_min = g.number("mu_min", mo.mu_min);
      if (!(mo.mu_min > 0 && mo.mu_min < 1)) g.fail("mu_min", "expected a value in (0, 1)");
      mo.subgrid = g.integer("subgrid", mo.subgrid, 1);
      if (mo.subgrid > 64) g.fail("subgrid", "expected at most 64 sub-cells per edge");
      mo.band = g.positive("band", mo.band);
      g.finish();
      BodyDesign bd;
      bd.body = &fb;
      bd.map = std::make_unique<DesignMap>(fb.mesh, LevelSet(std::move(feats), std::move(root), d->size()), mo);
      d->bodies.push_back(std::move(bd));
    }
    for (const auto& b : r.items("parameters")) {
      ParameterBinding pb;
      const std::string pname = b.string("parameter");
      pb.parameter = model().parameter_index(pname);
      if (pb.parameter < 0) {
        std::string avail;
        for (const auto& n : model().parameter_names()) avail += (avail.empty() ? "" : ", ") + n;
        b.fail("parameter", "unknown model parameter '" + pname + "' (parameters: " + avail + ")");
      }
      const std::string vname = b.string("variable");
      pb.variable = d->variable_index(vname);
      if (pb.variable < 0) b.fail("variable", "unknown design variable '" + vname + "'");
      pb.scale = b.number("scale", 1.0);
      pb.offset = b.number("offset", 0.0);
      b.finish();
      for (const auto& o : d->bindings)
        if (o.parameter == pb.parameter) b.fail("parameter", "parameter '" + pname + "' is bound twice");
      d->bindings.push_back(pb);
    }
    r.finish();
    cs.design = std::move(d);
  }

  /// The JSON entry each force element comes from, in the order they were added: the index of
  /// its first element, its JSON path and its name (bodies: inertia or finite elements; forces).
  struct Entry {
    size_t first;
    std::string path, name;
  };
  std::vector<Entry> force_entries;
  std::map<std::string, std::string> joint_paths;  ///< joint name → JSON path
  void begin_entry(const JsonReader& r, const std::string& name) {
    force_entries.push_back({model().forces().size(), r.path(), name});
  }

  Vec init_v;
  // Velocities the case gives (kept by the initial projection) and, per body that gives any,
  // its JSON path and unknowns [first, end).
  std::vector<char> held_v;
  struct GivenVelocity {
    std::string path;
    int first, end;
  };
  std::vector<GivenVelocity> given_v;
  // A body's unknowns [first, end) with the angle (rigid) or all (flexible) from `rotation_dof` on:
  // translations held when `translation`, the rest when `rotation`.
  void given_velocity(const JsonReader& r, int first, int rotation_dof, bool translation, bool rotation) {
    const int end = model().nq();
    held_v.resize(end, 0);
    for (int i = first; i < end; ++i) held_v[i] = i < rotation_dof ? translation : rotation;
    if (translation || rotation)
      given_v.push_back({r.path() + (r.has("velocity") ? "/velocity" : "/angular_velocity"), first, end});
  }
  std::map<std::string, bool> driver_relative;
  std::map<std::string, std::pair<size_t, size_t>> joint_elements;
  std::vector<std::pair<std::string, std::string>> pending_forces;
};

// Bodies that no constraint, mass or force touches would make the iteration matrix singular;
// report them by name before running.
void check_determined(const Case& cs, const JsonReader& root) {
  const Model& m = *cs.model;
  std::vector<char> touched(m.nq(), 0);
  for (const auto& c : m.constraints())
    for (int d : c->dofs()) touched[d] = 1;
  for (const auto& b : m.rigid_bodies()) {
    const double mass = m.params().scalars[b.mass_param], J = m.params().scalars[b.inertia_param];
    const bool constrained = touched[b.dof0] || touched[b.dof0 + 1] || touched[b.dof0 + 2];
    if (!constrained && mass == 0 && J == 0)
      root.fail("bodies", "rigid body '" + b.name + "' has no mass and no joint: its motion is not determined");
  }
}

}  // namespace

// Redundant or conflicting constraints, seen before any run: the rows of Φ_q at the initial
// positions must be independent (rank-revealing sparse QR of Φ_qᵀ). The dependent rows are
// named by their joints — e.g. a duplicated bearing, or two prismatic joints that both lock a
// body's rotation — instead of a singular iteration matrix later blaming another joint.
static void check_constraint_rank(const Case& cs) {
  const Model& m = *cs.model;
  if (m.nc() == 0 || !cs.check_constraints) return;
  SpMat Jt = m.constraint_jacobian(0.0, m.initial_positions(), m.params()).transpose();
  Jt.makeCompressed();
  Eigen::SparseQR<SpMat, Eigen::COLAMDOrdering<int>> qr;
  qr.compute(Jt);
  if (qr.info() != Eigen::Success || qr.rank() >= m.nc()) return;
  std::string dependent;
  const auto& perm = qr.colsPermutation().indices();
  const int shown = std::min<int>(m.nc() - static_cast<int>(qr.rank()), 6);
  for (int k = static_cast<int>(qr.rank()); k < static_cast<int>(qr.rank()) + shown; ++k)
    dependent += (dependent.empty() ? "" : "; ") + m.describe_unknown(m.nq() + perm[k]);
  throw Error(cs.file, "/joints",
              std::to_string(m.nc() - qr.rank()) + " of the " + std::to_string(m.nc()) +
                  " constraint equations are redundant or conflicting at t = 0 (the rows of the constraint "
                  "Jacobian are dependent): " + dependent +
                  " — remove the duplicated joint, or unlock a rotation (\"lock_rotation\": false) locked twice");
}

// Values beyond double precision, seen before any run: every force element's residual and
// iteration-matrix block at the initial state with the case's h (the first Newton matrix of
// Algorithm 1, S = β′M + γ′C_t + K_t), the assembled matrix with the automatic scaling k = ζ, and
// the constraints Φ, Φ_t and γ at t = 0 must be finite. A mass of 1e308 kg, for instance,
// overflows in β′M; without this check the KLU factorization of the start system fails and blames
// an unrelated joint. The message names the JSON entry and its parameters.
static void check_finite_start(const Case& cs, const std::vector<Loader::Entry>& entries,
                               const std::map<std::string, std::string>& joint_paths) {
  const Model& m = *cs.model;
  const ModelParams& p = m.params();
  const AlphaCoefficients c = AlphaCoefficients::make(cs.simulation.rho_inf, cs.simulation.h);
  const Coefficients co{c.beta_p, c.gamma_p, 1.0};
  char when[160];
  std::snprintf(when, sizeof when, "at t = 0 with h = %g s (β′ = %.3g s⁻²)", cs.simulation.h, c.beta_p);
  auto entry_of = [&](size_t force) -> const Loader::Entry* {
    const Loader::Entry* e = nullptr;
    for (const auto& x : entries)
      if (x.first <= force) e = &x;
    return e;
  };
  auto parameters_of = [&](const std::string& name) {
    std::string out;
    char buf[64];
    const auto& names = m.parameter_names();
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i].rfind(name + ".", 0) == 0) {
        std::snprintf(buf, sizeof buf, "%s = %g", names[i].substr(name.size() + 1).c_str(), p.scalars[i]);
        out += (out.empty() ? "" : ", ") + std::string(buf);
      }
    return out.empty() ? std::string() : " (" + out + ")";
  };
  const Vec& q = cs.initial.q;
  const Vec& v = cs.initial.v;
  const auto& forces = m.forces();
  double s_max = 0;  // the largest iteration-matrix entry of one element, and which element
  size_t f_max = 0;
  for (size_t f = 0; f < forces.size(); ++f) {
    const auto d = forces[f]->dofs();
    const auto nd = static_cast<Eigen::Index>(d.size());
    LocalState ls;
    ls.q.resize(nd), ls.v.resize(nd), ls.a.setZero(nd);
    for (Eigen::Index i = 0; i < nd; ++i) ls.q[i] = q[d[i]], ls.v[i] = v[d[i]];
    LocalVec r = LocalVec::Zero(nd);
    LocalMat S = LocalMat::Zero(nd, nd);
    forces[f]->evaluate(ls, p, r, &co, &S);
    if (r.allFinite() && S.allFinite()) {
      if (nd && S.cwiseAbs().maxCoeff() > s_max) s_max = S.cwiseAbs().maxCoeff(), f_max = f;
      continue;
    }
    const Loader::Entry* e = entry_of(f);
    throw Error(cs.file, e ? e->path : "", forces[f]->describe() + ": its forces or iteration matrix are not finite " +
                                               when + ": a value is beyond double precision; check its parameters" +
                                               (e ? parameters_of(e->name) : "") + ", its initial velocity and the gravity");
  }
  // The factorization of [S kΦ_qᵀ; kΦ_q 0] forms products of entries (k²/S in the pivots of the
  // constraint rows, with k the mean diagonal of S): entries beyond ~1e100 overflow there even
  // though each one is finite (a spring of 1e308 N/m failed as "consistent initial accelerations
  // are not finite"). Physical models are far below: a steel plate's stiffness entries are of the
  // order E·t ≈ 2e9 N/m, β′M at h = 1 µs about 1e12 times its masses.
  constexpr double kMaxEntry = 1e100;
  if (s_max > kMaxEntry) {
    const Loader::Entry* e = entry_of(f_max);
    char buf[96];
    std::snprintf(buf, sizeof buf, "its iteration-matrix entries reach %.3g ", s_max);
    throw Error(cs.file, e ? e->path : "", forces[f_max]->describe() + ": " + buf + when +
                                               ": beyond 1e100 the sparse factorization overflows; check its parameters" +
                                               (e ? parameters_of(e->name) : ""));
  }
  Vec phi, phi_t, gamma;
  m.constraints(0.0, q, p, phi);
  m.constraint_time_terms(0.0, q, v, p, phi_t, gamma);
  for (Eigen::Index i = 0; i < phi.size(); ++i)
    if (!std::isfinite(phi[i]) || !std::isfinite(phi_t[i]) || !std::isfinite(gamma[i])) {
      std::string path = "/joints";
      for (size_t k = 0; k < m.constraints().size(); ++k)
        if (i >= m.constraint_offset(static_cast<int>(k)) && i < m.constraint_offset(static_cast<int>(k)) + m.constraints()[k]->size())
          if (auto it = joint_paths.find(m.constraints()[k]->name()); it != joint_paths.end()) path = it->second;
      throw Error(cs.file, path, m.describe_unknown(m.nq() + static_cast<int>(i)) +
                                     ": the constraint, its velocity or its acceleration term is not finite at t = 0 "
                                     "(a position, velocity or driver law value beyond double precision)");
    }
  const double k = GeneralizedAlpha::automatic_scaling(m, p, cs.initial, c);
  // A scaling or penalty far from the automatic one makes the constraint rows dominate (or vanish
  // in) the iteration matrix: the results then carry round-off of that ratio (ζ = 1e300 gave a
  // side force of 1e277 N, exit 0). The results do not depend on them within 1e-3 ... 1e3
  // (test_pendulum); more than 1e8 away is refused.
  for (const auto& [key, value] : {std::pair<const char*, double>{"k", cs.simulation.k}, {"zeta", cs.simulation.zeta}})
    if (value > 0 && std::isfinite(k) && k > 0 && (value > 1e8 * k || value < 1e-8 * k)) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "%g is more than 1e8 times away from the automatic scaling %.3g of this model "
                                     "(give 0 for the automatic value)", value, k);
      throw Error(cs.file, std::string("/simulation/") + key, buf);
    }
  std::vector<double> vals;
  m.iteration_matrix(cs.initial, p, co, cs.simulation.k > 0 ? cs.simulation.k : k,
                     cs.simulation.zeta > 0 ? cs.simulation.zeta : k, vals);
  const auto& pat = m.pattern();
  for (int col = 0; col < pat.n; ++col)
    for (int at = pat.col_ptr[col]; at < pat.col_ptr[col + 1]; ++at)
      if (!std::isfinite(vals[at]) || !std::isfinite(k))
        throw Error(cs.file, "/simulation",
                    "the iteration matrix is not finite " + std::string(when) + " in the equations of " +
                        m.describe_unknown(col) + " (the sum of its masses or stiffnesses overflows; automatic "
                        "scaling k = " + std::to_string(k) + "): a value is beyond double precision");
}

// Initial velocities the case gives are kept; the others follow from the constraints
// (integrators/initial_state.hpp). Given velocities that contradict the constraints are an input
// error naming the first body concerned. Positions and velocities are projected here, so that
// every run starts from the same consistent state.
template <class Given>
static void hold_given_velocities(Case& cs, std::vector<char> held, const std::vector<Given>& given) {
  const Model& m = *cs.model;
  if (given.empty() || m.nc() == 0 || !cs.simulation.project_initial) return;
  held.resize(m.nq(), 0);
  SparseLU lu;
  lu.analyze(m.pattern());
  ProjectionReport rep;
  State s = cs.initial;
  const Status st = project_initial_state(m, m.params(), s, lu, 1e-13 * m.length_scale(), &rep, &held);
  if (st.ok()) cs.initial = s;
  if (st.ok() || rep.conflicting_rows.empty()) return;  // other failures: reported by the run
  std::string path = "/bodies";
  for (const auto& g : given)
    for (int j : rep.conflicting_held)
      if (j >= g.first && j < g.end && path == "/bodies") path = g.path;
  throw Error(cs.file, path,
              st.message + " — give only the velocities that determine the motion (the others are computed), "
                           "or velocities that satisfy the joints and drivers at t = 0");
}

Case load_case_json(const nlohmann::json& j, const std::string& file_label, const std::string& base_dir) {
  Case cs;
  cs.file = file_label;
  cs.raw = j;
  cs.model = std::make_unique<Model>();
  Loader L(cs, base_dir);
  const JsonReader root(j, file_label);
  if (!root.is_object()) root.fail("expected a JSON object at the top level");
  cs.name = root.string("name", fs::path(file_label).stem().string());
  if (root.has("gravity")) cs.model->params().gravity = root.vec2("gravity");
  const auto bodies = root.items("bodies", true);
  if (bodies.empty()) root.fail("bodies", "expected at least one body");
  for (const auto& b : bodies) {
    const std::string name = b.string("name");
    L.unique_name(b, name);
    if (name == "ground") b.fail("name", "'ground' is reserved");
    const std::string type = b.one_of("type", {"rigid", "flexible"});
    L.begin_entry(b, name);
    if (type == "rigid") L.rigid_body(b, name);
    else L.flexible_body(b, name);
  }
  int i = 0;
  for (const auto& jt : root.items("joints")) L.joint(jt, i++);
  i = 0;
  for (const auto& f : root.items("forces")) L.force(f, i++);
  if (auto d = root.optional_child("design")) L.design(*d);
  if (auto o = root.optional_child("optimization")) cs.optimization = o->raw();
  L.simulation(root.child("simulation"));
  if (auto out = root.optional_child("output")) {
    cs.output.csv_stride = out->integer("csv_stride", 1, 1);
    cs.output.vtu_stride = out->integer("vtu_stride", 0, 0);
    for (const auto& m : out->items("measures")) L.measure(m);
    for (const auto& r : out->items("responses")) L.response(r);
    out->finish();
  }
  root.finish();
  check_determined(cs, root);
  cs.model->finalize();
  check_constraint_rank(cs);
  // constraint-force measures: rows are known now
  size_t pi = 0;
  for (auto& m : cs.measures) {
    if (m) continue;
    const auto& [nm, jn] = L.pending_forces[pi++];
    const auto [b, e] = L.joint_elements.at(jn);
    std::vector<int> rows;
    for (size_t k = b; k < e; ++k)
      for (int r = 0; r < cs.model->constraints()[k]->size(); ++r) rows.push_back(cs.model->constraint_offset(static_cast<int>(k)) + r);
    m = std::make_unique<ConstraintForceMeasure>(nm, rows);
  }
  for (const auto& [jn, range] : L.joint_elements) {
    std::vector<int> rows;
    for (size_t k = range.first; k < range.second; ++k)
      for (int r = 0; r < cs.model->constraints()[k]->size(); ++r) rows.push_back(cs.model->constraint_offset(static_cast<int>(k)) + r);
    cs.joint_rows[jn] = rows;
  }
  // every response window must contain a time step of the run [0, t_end]
  for (size_t i = 0; i < cs.responses.size(); ++i) {
    const auto& r = cs.responses[i];
    const double h = cs.simulation.h, a = std::max(r.t0, 0.0), b = std::min(r.t1, cs.simulation.t_end);
    const double k_first = std::ceil(a / h - 1e-9), k_last = std::floor(b / h + 1e-9);
    if (b < a || k_last < k_first)
      throw Error(file_label, "/output/responses/" + std::to_string(i) + (r.t0 > -1e299 || r.t1 < 1e299 ? "/window" : ""),
                  "the window (" + r.window_text + ") contains no time step of the run [0, " +
                      std::to_string(cs.simulation.t_end) + "] s with h = " + std::to_string(h));
  }
  if (cs.design) cs.design->apply(cs.design->initial(), cs.model->params());
  cs.initial.t = 0;
  cs.initial.q = cs.model->initial_positions();
  cs.initial.v = L.init_v;
  cs.initial.v.conservativeResize(cs.model->nq());
  cs.initial.a.setZero(cs.model->nq());
  cs.initial.lambda.setZero(cs.model->nc());
  check_finite_start(cs, L.force_entries, L.joint_paths);
  hold_given_velocities(cs, L.held_v, L.given_v);
  // every measure must be finite at the initial state (a point 1e300 m away made a distance, and
  // every response of it, Inf or NaN in a run reported complete)
  std::vector<double> vals;
  for (size_t i = 0; i < cs.measures.size(); ++i) {
    vals.assign(cs.measures[i]->components().size(), 0.0);
    cs.measures[i]->evaluate(*cs.model, cs.initial, cs.model->params(), vals.data());
    for (double v : vals)
      if (!std::isfinite(v))
        throw Error(file_label, "/output/measures/" + std::to_string(i),
                    "measure '" + cs.measures[i]->name() + "' is not finite at t = 0 (a point or value beyond double precision)");
  }
  return cs;
}

Case load_case(const std::string& path) {
  if (const auto why = unreadable_file_reason(path); !why.empty()) throw Error(path, "", "case file: " + why);
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path, "", "cannot open case file");
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str();
  check_json_depth(text, path);  // before nlohmann::json, which parses recursively
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(path, "byte " + std::to_string(e.byte), std::string("invalid JSON: ") + e.what());
  } catch (const nlohmann::json::exception& e) {  // e.g. out_of_range: a number like 1e999 (found by fuzzing)
    throw Error(path, "", std::string("invalid JSON: ") + e.what());
  }
  Case cs = load_case_json(j, path, fs::path(path).parent_path().string());
  cs.sha256 = sha256_hex(text);
  return cs;
}

}  // namespace lsmbs
