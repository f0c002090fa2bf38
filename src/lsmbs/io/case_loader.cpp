#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "lsmbs/core/file_check.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/initial_state_file.hpp"
#include "lsmbs/io/json_reader.hpp"
#include "lsmbs/io/model_kinds.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/sha256.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/records/json.hpp"
#include "lsmbs/sensitivity/conditions.hpp"

// The JSON loader: JSON → ModelBuilder calls (mbs/model_builder.hpp owns what a body, joint or
// force means), plus the sections that are the case file's own (simulation options, output
// measures and responses, design). It checks types, ranges and unknown keys, and maps the
// builder's errors, which name an entity and an argument, to the JSON path of the entry. The
// checks of the built case (constraint rank, finite start, placement, …) are prepare_case's
// (io/case_start.cpp), which a case changed after loading runs again.

namespace lsmbs {

Error locate(const std::string& case_file, const SetupError& e) {
  // subjects are dotted names of the case's sections; responses and measures sit under /output
  if (e.subject().empty()) return Error(case_file, "", e.reason());
  std::string path = "/" + e.subject();
  for (auto& ch : path)
    if (ch == '.') ch = '/';
  if (path.rfind("/responses", 0) == 0 || path.rfind("/measures", 0) == 0) path = "/output" + path;
  return Error(case_file, path, e.reason());
}

Error locate(const Case& cs, const SetupError& e) {
  if (!e.entity().empty())
    if (const auto at = cs.paths.find(e.entity()); at != cs.paths.end())
      return Error(cs.file, at->second + (e.field().empty() ? "" : "/" + e.field()), e.reason());
  return locate(cs.file, e);
}

namespace {

namespace fs = std::filesystem;

std::string format_g(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// Elements of a rectangle mesh at most: a cap that keeps a typo (a zero or two too many) from
// exhausting the memory; 5e6 elements are 10^7 unknowns, beyond what a run of this testbed
// finishes.
constexpr double kMaxRectangleElements = 5e6;
constexpr double kMaxSolidElements = 2e6;

// A builder error at the JSON entry `r`: the builder names the argument at fault as the case format
// does ("a/body", "node_set", or nothing for the entry as a whole), a path below the entry.
[[noreturn]] void fail_at(const JsonReader& r, const ModelError& e) {
  if (e.field().empty()) r.fail(e.message());
  r.fail(e.field(), e.message());
}

// Runs a builder call for the JSON entry `r` (errors: fail_at).
template <class F>
decltype(auto) at_entry(const JsonReader& r, F&& call) {
  try {
    return call();
  } catch (const ModelError& e) {
    fail_at(r, e);
  }
}

// Runs a query by name (a body, joint or driver named by the key `key` of `r`): its error is
// reported at that key.
template <class F>
decltype(auto) at_key(const JsonReader& r, const std::string& key, F&& call) {
  try {
    return call();
  } catch (const ModelError& e) {
    r.fail(key, e.message());
  }
}

struct Loader : KindReader {
  Loader(Case& c, std::string dir) : cs(c), base_dir(std::move(dir)) {}
  Case& cs;
  std::string base_dir;
  ModelBuilder builder_;
  std::map<std::string, std::string> paths;  ///< JSON path of each body, joint and force by name
  bool spatial = false;  ///< "dimension": 3: spatial bodies and the spatial kinds

  std::string resolve(const std::string& f) {
    const std::string path = fs::path(f).is_absolute() ? f : (fs::path(base_dir) / f).string();
    files_read.insert(path);
    return path;
  }
  std::set<std::string> files_read;  ///< every file name resolved (hashed once loaded)

  // A named entry (body, joint or force): its name is checked as soon as it is read.
  void entry(const JsonReader& r, const std::string& name, bool body) {
    at_entry(r, [&] { builder_.check_name(name, body); });
    paths.emplace(name, r.path());
  }

  // ---------------------------------------------------------------- time laws
  std::shared_ptr<const TimeLaw> law(const JsonReader& r) override {
    const std::string type = r.one_of("type", {"trapezoid", "ramp", "table", "constant"});
    std::shared_ptr<const TimeLaw> out;
    try {
      if (type == "trapezoid") {
        out = std::make_shared<TrapezoidLaw>(r.number("from"), r.number("to"),
                                             r.positive("acceleration"), r.positive("speed"),
                                             r.number("start", 0.0));
      } else if (type == "ramp") {
        out = std::make_shared<RampLaw>(r.number("from", 0.0), r.number("speed"),
                                        r.positive("ramp_time"), r.number("start", 0.0));
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

  Table1D table(const JsonReader& r) override {
    const auto interp = r.one_of("interpolation", {"cubic", "linear"}, "cubic") == "cubic"
                            ? Table1D::Interp::kCubic
                            : Table1D::Interp::kLinear;
    const double period = r.non_negative("period", 0.0);
    // x_scale multiplies the abscissae (which must increase): a positive factor; y_scale any factor
    const double xs = r.positive("x_scale", 1.0), ys = r.number("y_scale", 1.0);
    if (r.has("file") && r.has("points"))
      r.fail("expected either \"file\" or \"points\", not both");
    if (r.has("file")) {
      const std::string f = resolve(r.string("file"));
      try {
        return Table1D::read_csv(f, interp, period, xs, ys);
      } catch (
          const Error& e) {  // name the case's JSON path too (the message names the table file)
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
  // Which keys a point object may have depends on its body: "at" / "at_global" on a rigid body,
  // "node" / "nearest" on a flexible one. The builder resolves the point (unknown body, node
  // index out of range) while the object is read.
  Point point(const JsonReader& r) override {
    if (r.is_string()) {
      if (r.as_string() == "ground")
        r.fail("a ground point needs coordinates: {\"ground\": [x, y]}");
      r.fail(
          "expected a point object ({\"ground\": [x, y]}, {\"body\": name, \"at\": [x, y]}, "
          "{\"body\": name, \"node\": i})");
    }
    if (!r.is_object()) r.fail("expected a point object");
    if (r.has("ground")) {
      const Point p = Point::ground(r.vec2("ground"));
      r.finish();
      return p;
    }
    const std::string body = r.string("body");
    Point p = Point::at(body);  // an unknown body: the builder names it below
    switch (builder_.body_kind(body)) {
      case ModelBuilder::BodyKind::kRigid:
        if (r.has("at_global"))
          p = Point::at_global(body, r.vec2("at_global"));
        else
          p = Point::at(body, r.vec2("at", Vec2::Zero()));
        break;
      case ModelBuilder::BodyKind::kFlexible:
        if (r.has("node"))
          p = Point::node(body, r.integer("node", 0));
        else if (r.has("nearest"))
          p = Point::nearest(body, r.vec2("nearest"));
        else
          r.fail(
              "a point on a flexible body needs \"node\": index or \"nearest\": [x, y] (mesh "
              "frame)");
        break;
      case ModelBuilder::BodyKind::kNone:
        break;
    }
    at_entry(r, [&] { return builder_.resolve(p); });
    r.finish();
    return p;
  }

  // ---------------------------------------------------------------- bodies
  void rigid_body(const JsonReader& r, const std::string& name) {
    RigidBodyOptions o;
    o.position = r.vec2("position", Vec2::Zero());
    o.angle = r.number("angle", 0.0);
    o.com = r.vec2("com", Vec2::Zero());
    o.mass = r.non_negative("mass", 0.0);
    o.inertia = r.non_negative("inertia", 0.0);
    if (r.has("velocity")) o.velocity = r.vec2("velocity");
    if (r.has("angular_velocity")) o.angular_velocity = r.number("angular_velocity");
    r.finish();
    at_entry(r, [&] { builder_.rigid_body(name, o); });
  }

  // A spatial rigid body ("dimension": 3): centre of mass, principal moments and axes.
  void spatial_body(const JsonReader& r, const std::string& name) {
    SpatialBodyOptions o;
    o.mass = r.non_negative("mass", 0.0);
    o.inertia = r.vec3("inertia", Vec3::Zero());
    o.position = r.vec3("position", Vec3::Zero());
    if (auto ori = r.optional_child("orientation")) o.orientation = orientation(*ori);
    if (r.has("velocity")) o.velocity = r.vec3("velocity");
    if (r.has("angular_velocity")) o.angular_velocity = r.vec3("angular_velocity");
    r.finish();
    at_entry(r, [&] { builder_.spatial_body(name, o); });
  }

  // The Gmsh file of a mesh entry {"type": "gmsh", "file", "scale"} (2D: Mesh2D, 3D: SolidMesh),
  // its coordinates times scale; a file's error names the case entry that referenced it.
  template <class MeshT>
  MeshT gmsh_mesh(const JsonReader& m) {
    const std::string f = resolve(m.string("file"));
    MeshT mesh;
    try {
      mesh = MeshT::read_gmsh(f);
    } catch (const Error& e) {
      throw Error(std::string(e.what()) + " (referenced from " + cs.file + ": " + m.path() +
                  "/file)");
    }
    const double sc = m.positive("scale", 1.0);
    for (auto& x : mesh.nodes) {
      x *= sc;
      if (!x.allFinite() || x.norm() > 1e100)  // beyond 1e100 m the element integrals overflow
        m.fail("scale",
               "the scaled mesh coordinates are out of range (scale " + format_g(sc) + ")");
    }
    return mesh;
  }

  // A 3D solid body ("dimension": 3, "type": "solid"): a box of hexahedra or a Gmsh mesh of
  // tetrahedra and hexahedra, St Venant–Kirchhoff.
  void solid_body(const JsonReader& r, const std::string& name) {
    const JsonReader m = r.child("mesh");
    SolidMesh mesh;
    if (m.one_of("type", {"box", "gmsh"}) == "gmsh") {
      mesh = gmsh_mesh<SolidMesh>(m);
      if (mesh.num_elements() > kMaxSolidElements)
        m.fail("file", "the mesh has " + std::to_string(mesh.num_elements()) +
                           " cells; a solid body has at most " +
                           std::to_string(static_cast<long>(kMaxSolidElements)));
    } else {
      const Vec3 origin = m.vec3("origin", Vec3::Zero()), size = m.vec3("size");
      if (!(size.minCoeff() > 0)) m.fail("size", "expected three positive lengths");
      const JsonReader el = m.child("elements");
      if (!el.is_array() || el.size() != 3) el.fail("expected [nx, ny, nz]");
      std::array<int, 3> n{};
      double cells = 1;
      for (size_t k = 0; k < 3; ++k) {
        const double v = el.at(k).as_number();
        if (v < 1 || v != std::floor(v) || v > 1e6)
          el.fail("expected three positive integers [nx, ny, nz]");
        n[k] = static_cast<int>(v);
        cells *= v;
      }
      if (cells > kMaxSolidElements)
        el.fail("a box mesh has at most " + std::to_string(static_cast<long>(kMaxSolidElements)) +
                " elements (nx × ny × nz)");
      mesh = SolidMesh::box(origin, size, n);
    }
    m.finish();
    const JsonReader mat = r.child("material");
    SolidBodyOptions o;
    o.E = mat.positive("E");
    o.nu = mat.number("nu");
    if (!(o.nu >= 0 && o.nu < 0.5)) mat.fail("nu", "expected Poisson's ratio in [0, 0.5)");
    o.rho = mat.positive("rho");
    mat.finish();
    o.formulation = r.one_of("formulation", {"enhanced", "full"}, "enhanced") == "full"
                        ? HexElement::Formulation::kFull
                        : HexElement::Formulation::kEnhanced;
    if (r.has("formulation") && std::none_of(mesh.cells.begin(), mesh.cells.end(),
                                             [](const auto& c) { return c.size() == 8; }))
      r.fail("formulation",
             "applies to hexahedra; this mesh has tetrahedra only (constant strain, no variants)");
    r.finish();
    at_entry(r, [&] { builder_.solid_body(name, std::move(mesh), o); });
  }

  // A rotation: {"axis": [x, y, z], "angle": rad}, or its matrix by rows [[…], […], […]]
  // (columns: the principal axes in ground coordinates).
  static Mat3 orientation(const JsonReader& r) {
    if (r.is_object()) {
      const Vec3 axis = r.vec3("axis");
      if (!(axis.norm() > 0)) r.fail("axis", "expected a non-zero direction");
      const double angle = r.number("angle");
      r.finish();
      return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
    }
    const auto& j = r.raw();
    if (!j.is_array() || j.size() != 3)
      r.fail("expected {\"axis\": [x, y, z], \"angle\": rad} or a 3 × 3 matrix by rows");
    Mat3 R;
    for (int i = 0; i < 3; ++i) {
      const auto& row = j[static_cast<size_t>(i)];
      if (!row.is_array() || row.size() != 3 || !row[0].is_number() || !row[1].is_number() ||
          !row[2].is_number())
        r.fail(std::to_string(i), "expected a row of three numbers");
      for (int c = 0; c < 3; ++c) R(i, c) = row[static_cast<size_t>(c)].get<double>();
    }
    return R;
  }

  void flexible_body(const JsonReader& r, const std::string& name) {
    Mesh2D mesh;
    const JsonReader m = r.child("mesh");
    const std::string mt = m.one_of("type", {"rectangle", "gmsh"});
    if (mt == "rectangle") {
      const Vec2 o = m.vec2("origin", Vec2::Zero()), sz = m.vec2("size");
      if (!(sz.x() > 0 && sz.y() > 0)) m.fail("size", "expected positive lengths");
      const JsonReader el = m.child("elements");
      if (!el.is_array() || el.size() != 2) el.fail("expected [nx, ny]");
      const double nx = el.at(0).as_number(), ny = el.at(1).as_number();
      if (nx < 1 || ny < 1 || nx != std::floor(nx) || ny != std::floor(ny))
        el.fail("expected two positive integers [nx, ny]");
      if (nx * ny > kMaxRectangleElements) {
        char msg[160];
        std::snprintf(msg, sizeof msg,
                      "[%.15g, %.15g] is %.15g elements; a rectangle mesh has at most %.0f "
                      "(nx × ny)",
                      nx, ny, nx * ny, kMaxRectangleElements);
        el.fail(msg);
      }
      // quadrilaterals, or each split into two triangles (the 3-node element's structured mesh)
      const std::string cells = m.one_of("cells", {"quad4", "tri3"}, "quad4");
      mesh = Mesh2D::rectangle(o.x(), o.y(), sz.x(), sz.y(), static_cast<int>(nx),
                               static_cast<int>(ny), cells);
    } else {
      if (m.has("cells"))
        m.fail("cells",
               "applies to rectangle meshes; a Gmsh file's cells are the elements it lists");
      mesh = gmsh_mesh<Mesh2D>(m);
    }
    m.finish();
    FlexibleBodyOptions o;
    if (auto pl = r.optional_child("placement")) {
      o.origin = pl->vec2("origin", Vec2::Zero());
      o.angle = pl->number("angle", 0.0);
      pl->finish();
    }
    const JsonReader mat = r.child("material");
    o.E = mat.positive("E");
    o.nu = mat.number("nu");
    if (!(o.nu >= 0 && o.nu < 0.5)) mat.fail("nu", "expected Poisson's ratio in [0, 0.5)");
    o.rho = mat.positive("rho");
    mat.finish();
    o.thickness = r.positive("thickness");
    o.full_integration =
        r.one_of("integration", {"selective-shear", "full"}, "selective-shear") == "full";
    // Node sets by selector (mesh frame), added to the mesh's own (rectangle sides, Gmsh groups).
    if (auto ns = r.optional_child("node_sets")) {
      if (!ns->is_object()) ns->fail("expected an object {name: selector}");
      for (const auto& key : ns->keys()) {
        const JsonReader s = ns->child(key);
        const double tol =
            s.has("tolerance") ? s.positive("tolerance") : -1.0;  // -1: the mesh's default
        std::vector<int> sel;
        if (s.has("line_x"))
          sel = mesh.nodes_on_line_x(s.number("line_x"), tol);
        else if (s.has("line_y"))
          sel = mesh.nodes_on_line_y(s.number("line_y"), tol);
        else if (s.has("circle")) {
          const JsonReader c = s.child("circle");
          sel = mesh.nodes_on_circle(c.vec2("center"), c.positive("radius"), tol);
          c.finish();
        } else if (s.has("box")) {
          const JsonReader c = s.child("box");
          sel = mesh.nodes_in_box(c.vec2("min"), c.vec2("max"));
          c.finish();
        } else if (s.has("nodes")) {
          for (const auto& it : s.items("nodes")) {
            const double v = it.as_number();
            if (v < 0 || v >= mesh.num_nodes() || v != std::floor(v))
              it.fail("expected a node index of the mesh");
            sel.push_back(static_cast<int>(v));
          }
        } else {
          s.fail("expected a selector: line_x, line_y, circle, box or nodes");
        }
        s.finish();
        if (sel.empty()) s.fail("the selector selects no node of body '" + name + "'");
        mesh.node_sets[key] = sel;
      }
    }
    if (r.has("velocity")) o.velocity = r.vec2("velocity");
    if (r.has("angular_velocity")) o.angular_velocity = r.number("angular_velocity");
    r.finish();
    try {  // the builder checks the element geometry (inverted or degenerate quadrilaterals)
      builder_.flexible_body(name, std::move(mesh), o);
    } catch (const ModelError& e) {
      if (e.field() == "mesh")
        r.fail("mesh", e.message() + " (check the mesh's coordinates: origin, size, scale)");
      fail_at(r, e);
    }
  }

  // ---------------------------------------------------------------- joints, forces, measures
  // An entry of a section of the table of model kinds (io/model_kinds.hpp): its type, its name
  // (checked as soon as it is read), then what its kind reads. An unnamed joint or force gets
  // "<type>_<index>".
  void kind_entry(const JsonReader& r, const std::string& section, int index) {
    const std::string type =
        r.one_of("type", spatial ? spatial_kind_types(section) : kind_types(section));
    const ModelKind& kind = spatial ? *find_spatial_kind(section, type) : *find_kind(section, type);
    std::string name;
    if (section == "measures") {
      name = r.string("name");
      // constraint_force measures are placeholders (null) until the model is built: their names
      // are pending
      for (const auto& m : cs.measures)
        if (m && m->name() == name) r.fail("name", "duplicate measure name '" + name + "'");
      for (const auto& pending : pending_forces)
        if (pending.first == name) r.fail("name", "duplicate measure name '" + name + "'");
    } else {
      name = r.string("name", type + "_" + std::to_string(index));
      entry(r, name, false);
    }
    kind.read(*this, r, name);
    r.finish();
  }

  // KindReader
  ModelBuilder& builder() override { return builder_; }
  void add_measure(std::unique_ptr<Measure> m) override { cs.measures.push_back(std::move(m)); }
  void add_constraint_force(const std::string& name, const std::string& joint) override {
    pending_forces.emplace_back(name, joint);
    cs.measures.push_back(nullptr);  // filled after build() (rows known then)
  }

  // ---------------------------------------------------------------- measures and responses
  // c0 + Σ w_i (measure column)_i over columns of measures listed before this one
  std::unique_ptr<Measure> combination(const JsonReader& r, const std::string& name) override {
    std::vector<CombinationMeasure::Term> terms;
    std::string unit;
    const StressMeasure* stress = nullptr;
    bool other_in_params = false;
    for (const auto& t : r.items("terms", true)) {
      const std::string col = t.string("measure");
      const double w = t.number("weight", 1.0);
      const Measure* found = nullptr;
      int component = -1;
      for (const auto& m : cs.measures) {
        if (!m) continue;  // a constraint force, filled after the build
        const auto comps = m->components();
        for (size_t c = 0; c < comps.size(); ++c)
          if (comps[c] == col) found = m.get(), component = static_cast<int>(c);
      }
      if (!found) {
        for (const auto& pending : pending_forces)
          if (col == pending.first || col.rfind(pending.first + ".", 0) == 0)
            t.fail("measure", "'" + col +
                                  "' is a constraint force: its scaling belongs to the run, and "
                                  "combinations do not take one");
        t.fail("measure", "unknown measure column '" + col +
                              "' (a column of a measure listed before this one, e.g. 'tip.x')");
      }
      const std::string u = found->units()[static_cast<size_t>(component)];
      if (unit.empty())
        unit = u;
      else if (u != unit)
        t.fail("measure", "'" + col + "' is in " + u + ", the terms before it in " + unit +
                              ": a combination adds quantities of one unit");
      if (const auto* sm = dynamic_cast<const StressMeasure*>(found)) {
        if (stress && stress != sm && stress->body_name() != sm->body_name())
          t.fail("measure",
                 "stresses of two bodies: their exact design derivatives do not add "
                 "up in one combination; combine each body's separately");
        stress = sm;
      } else if (found->depends_on_params()) {
        other_in_params = true;
      }
      if (stress && other_in_params)
        t.fail("measure",
               "a stress combined with a measure that depends on the design's "
               "parameters (mass, energy): the stress's exact design derivative and "
               "the other's difference quotient cannot be added in one measure");
      terms.push_back({found, component, w});
      t.finish();
    }
    return std::make_unique<CombinationMeasure>(name, r.number("constant", 0.0), std::move(terms),
                                                unit);
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
    const std::string agg = r.one_of("aggregate", {"average", "average_eq45", "max", "min", "final",
                                                   "integral", "rms", "per_step", "ks"});
    using K = ResponseSpec::Kind;
    s.kind = agg == "average"        ? K::kAverage
             : agg == "average_eq45" ? K::kAverageEq45
             : agg == "max"          ? K::kMax
             : agg == "min"          ? K::kMin
             : agg == "final"        ? K::kFinal
             : agg == "integral"     ? K::kIntegral
             : agg == "rms"          ? K::kRms
             : agg == "per_step"     ? K::kPerStep
                                     : K::kKS;
    if (s.kind == K::kKS) s.ks = r.positive("ks");
    if (auto w = r.optional_child("window")) {
      if (w->has("phase")) {
        const std::string d = w->string("driver");
        const DriverInfo* drv = builder_.driver(d);
        if (!drv) w->fail("driver", "unknown driver '" + d + "'");
        const std::string ph = w->string("phase");
        bool found = false;
        std::string avail;
        for (const auto& p : drv->law->phases()) {
          avail += (avail.empty() ? "" : ", ") + p.name;
          if (p.name == ph) {
            s.t0 = p.t0, s.t1 = p.t1, found = true;
          }
        }
        if (!found)
          w->fail("phase", "driver '" + d + "' has no phase '" + ph +
                               "' (phases: " + (avail.empty() ? "none" : avail) + ")");
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
      } else {  // constraint-force measure (built after build()): components from the joint's
                // equations
        const auto& [nm, j] = pending_forces[pending_index(i)];
        const int m = builder_.joint_equations(j);
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
      const std::string nw =
          r.one_of("newton", {"full", "modified", "modified_across_steps"}, "full");
      using N = GeneralizedAlphaOptions::Newton;
      o.newton = nw == "full"       ? N::kFull
                 : nw == "modified" ? N::kModified
                                    : N::kModifiedAcrossSteps;
    }
    cs.check_constraints = r.boolean("check_constraints", true);
    o.ordering = r.one_of("ordering", {"amd", "nested_dissection"}, "amd") == "amd"
                     ? SparseLU::Ordering::kAmd
                     : SparseLU::Ordering::kNestedDissection;
    {
      const std::string ls = r.one_of("linear_solver", {"auto", "klu", "umfpack", "amg"}, "auto");
      if (ls == "amg" && !SparseLU::amg_available())
        r.fail("linear_solver",
               "\"amg\" needs a build of lsmbs with hypre (Debian's libhypre-dev: "
               "scripts/setup-deps.sh installs it; then rebuild); this build has none");
      o.linear_solver = ls == "auto"      ? SparseLU::Solver::kAuto
                        : ls == "klu"     ? SparseLU::Solver::kKlu
                        : ls == "umfpack" ? SparseLU::Solver::kUmfpack
                                          : SparseLU::Solver::kAmg;
    }
    o.k = r.non_negative("k", 0.0);
    o.zeta = r.non_negative("zeta", 0.0);
    o.force_floor = r.non_negative("force_floor", o.force_floor);
    if (auto msg = o.validate(); !msg.empty()) {
      const auto colon = msg.find(':');
      r.fail(msg.substr(0, colon), msg.substr(colon + 2));
    }
    r.finish();
  }

  // ---------------------------------------------------------------- design
  ParamBinding binding(const JsonReader& r, const std::string& key, const Design& d) {
    return binding(r.child(key), d);
  }

  ParamBinding binding(const JsonReader& v, const Design& d) {
    ParamBinding b;
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
    if (!r.is_object())
      r.fail("expected a feature name or {\"and\" | \"or\": [...]} or {\"not\": ...}");
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

  // A Design call for the entry r: its SetupError at r's field it names (below r), or at the
  // entry of the feature it names (`features`: feature name -> its entry), or at r.
  template <class F>
  void at_design(const JsonReader& r, F&& call,
                 const std::map<std::string, JsonReader>* features = nullptr) {
    try {
      call();
    } catch (const SetupError& e) {
      if (features && !e.entity().empty())
        if (const auto at = features->find(e.entity()); at != features->end())
          at->second.fail(e.reason());
      if (!e.field().empty()) r.fail(e.field(), e.reason());
      r.fail(e.reason());
    }
  }

  void variable(const JsonReader& v, Design& d) {
    const std::string name = v.string("name");
    const double lower = v.number("lower"), upper = v.number("upper"),
                 initial = v.number("initial");
    v.finish();
    at_design(v, [&] { d.add_variable(name, initial, lower, upper); });
  }

  // A feature entry: its parameters in the table's order (Feature's), each a number, a variable
  // name or {variable, scale, offset}; whether it is a non-design feature.
  Feature feature(const JsonReader& f, const Design& d, bool& non_design) {
    const std::string name = f.string("name");
    const std::string ts = f.one_of("type", kind_types("features"));
    bool ok = false;
    const auto type = Feature::parse_type(ts, &ok);
    std::vector<ParamBinding> ps;
    if (type == Feature::Type::kBSpline) {
      // control points [[x, y], …]: each coordinate a number or a variable binding
      const auto points = f.items("control_points", true);
      if (points.size() < 4)
        f.fail("control_points", "expected at least 4 control points [x, y] of a closed curve");
      for (const auto& pt : points) {
        if (!pt.is_array() || pt.size() != 2)
          pt.fail(
              "expected a control point [x, y] (each a number, a variable name or "
              "{\"variable\", \"scale\", \"offset\"})");
        ps.push_back(binding(pt.at(0), d));
        ps.push_back(binding(pt.at(1), d));
      }
    }
    for (const KindKey& key : find_kind("features", ts)->keys) {
      if (key.type != KeyType::kParameter) continue;
      if (!key.required && !f.has(key.name))
        ps.push_back(ParamBinding{});  // zero (an angle)
      else
        ps.push_back(binding(f, key.name, d));
    }
    // a non-design feature is solid inside and OR-ed with the region: material there whatever
    // the design features do
    non_design = f.boolean("non_design", false);
    if (non_design && f.has("hole"))
      f.fail("hole", "a non_design feature is solid inside (material forced there); drop \"hole\"");
    const bool hole = non_design ? false : f.boolean("hole", true);
    f.finish();
    return Feature(name, type, ps, hole);
  }

  // A 3D feature entry of a solid body's geometry: its parameters in Feature3's order, its frame
  // (a cylinder's axis, a super-ellipsoid's orientation, a pocket's or through-hole's face).
  Feature3 feature3(const JsonReader& f, const Design& d, const SolidMesh& mesh, bool& non_design) {
    const std::string name = f.string("name");
    bool ok = false;
    const auto type = Feature3::parse_type(f.one_of("type", Feature3::type_names()), &ok);
    Feature::Type profile = Feature::Type::kCircle;
    Frame3 frame;
    if (type == Feature3::Type::kPocket || type == Feature3::Type::kThroughHole) {
      profile =
          Feature::parse_type(f.one_of("profile", {"circle", "ellipse", "super_ellipse"}), &ok);
      frame = face_frame(f.child("face"), mesh);
    } else if (type == Feature3::Type::kCylinder) {
      const Vec3 axis = f.vec3("axis", Vec3::UnitZ());
      if (!(axis.norm() > 0)) f.fail("axis", "expected a non-zero direction");
      frame.axes = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), axis).toRotationMatrix();
    } else if (type == Feature3::Type::kSuperEllipsoid && f.has("orientation")) {
      const JsonReader o = f.child("orientation");
      frame.axes = orientation(o);
      const Mat3& R = frame.axes;
      const double off = (R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff();
      if (off > 1e-9 || R.determinant() < 0)
        o.fail("expected a rotation (orthonormal columns, determinant +1, to 1e-9): |RᵀR − I| = " +
               format_g(off) + ", det R = " + format_g(R.determinant()) +
               "; the semi-axes a, b, c size the shape (give {\"axis\": [x, y, z], \"angle\": "
               "rad}, or the matrix to full precision)");
    }
    std::vector<ParamBinding> ps;
    for (const std::string& key : Feature3::parameter_names(type, profile))
      if ((key == "angle" || key == "length") && !f.has(key))
        ps.push_back(ParamBinding{});  // zero: no rotation; a cylinder through everything
      else
        ps.push_back(binding(f, key, d));
    non_design = f.boolean("non_design", false);
    if (non_design && f.has("hole"))
      f.fail("hole", "a non_design feature is solid inside (material forced there); drop \"hole\"");
    const bool hole = non_design ? false : f.boolean("hole", true);
    f.finish();
    return Feature3(name, type, ps, hole, frame, profile);
  }

  // A pocket's or through-hole's face: a face of the mesh's bounding box by name, its profile's
  // (u, v) the face plane's two global coordinates in x, y, z order and w the depth into the
  // part; or {"origin", "normal" (into the part), "u_axis"}, v = normal × u_axis.
  static Frame3 face_frame(const JsonReader& r, const SolidMesh& mesh) {
    Frame3 fr;
    if (r.is_string()) {
      const std::vector<std::string> names = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
      const auto it = std::find(names.begin(), names.end(), r.as_string());
      if (it == names.end())
        r.fail(
            "expected a face of the body's bounding box (xmin, xmax, ymin, ymax, zmin, zmax) "
            "or {\"origin\", \"normal\", \"u_axis\"}");
      const int k = static_cast<int>(it - names.begin()) / 2;
      const bool max = (it - names.begin()) % 2 == 1;
      Vec3 lo = mesh.nodes.front(), hi = lo;
      for (const Vec3& x : mesh.nodes) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
      fr.origin = Vec3::Zero();
      fr.origin[k] = max ? hi[k] : lo[k];
      const int u = k == 0 ? 1 : 0, v = k == 2 ? 1 : 2;
      fr.axes.setZero();
      fr.axes(u, 0) = 1, fr.axes(v, 1) = 1, fr.axes(k, 2) = max ? -1 : 1;
      return fr;
    }
    fr.origin = r.vec3("origin");
    const Vec3 n = r.vec3("normal");
    if (!(n.norm() > 0)) r.fail("normal", "expected a non-zero direction (into the part)");
    Vec3 u = r.vec3("u_axis");
    const Vec3 w = n.normalized();
    u -= u.dot(w) * w;  // its part in the face's plane
    if (!(u.norm() > 1e-6 * r.vec3("u_axis").norm()) || !(u.norm() > 0))
      r.fail("u_axis", "expected a direction not parallel to the normal");
    r.finish();
    fr.axes.col(0) = u.normalized();
    fr.axes.col(2) = w;
    fr.axes.col(1) = w.cross(fr.axes.col(0));
    return fr;
  }

  // The features, region and mapping options of a geometry entry (planar or solid), each
  // feature read by parse(entry, non_design); returns every feature's entry by name.
  template <class Spec, class Parse>
  std::map<std::string, JsonReader> geometry_spec(const JsonReader& g, Spec& spec, Parse&& parse) {
    std::map<std::string, int> by_name;  // design features, by name: their index in the region
    std::map<std::string, JsonReader> entries;  // every feature's entry, by name
    for (const auto& f : g.items("features", true)) {
      const std::string name = f.string("name");
      if (entries.count(name)) f.fail("name", "duplicate feature name '" + name + "'");
      entries.emplace(name, f);
      bool non_design = false;
      auto feat = parse(f, non_design);
      if (!non_design) by_name[name] = static_cast<int>(spec.features.size());
      (non_design ? spec.non_design : spec.features).push_back(std::move(feat));
    }
    if (by_name.empty())
      g.fail("features",
             "every feature is non_design: non-design regions only keep material that the "
             "design features would remove; give at least one design feature");
    if (g.has("region")) {
      for (const auto& f : spec.non_design)
        if (g.child("region").raw().dump().find('"' + f.name() + '"') != std::string::npos)
          g.fail("region", "feature '" + f.name() +
                               "' is non_design: it is OR-ed with the region, not part of it");
      spec.region = region(g.child("region"), by_name);
    }
    MappingOptions& mo = spec.options;
    mo.mu_min = g.number("mu_min", mo.mu_min);
    if (!(mo.mu_min > 0 && mo.mu_min < 1)) g.fail("mu_min", "expected a value in (0, 1)");
    mo.subgrid = g.integer("subgrid", mo.subgrid, 1);
    // 3D: n³ sub-cells per cut element
    const int most = spatial ? 32 : 64;
    if (mo.subgrid > most)
      g.fail("subgrid", "expected at most " + std::to_string(most) + " sub-cells per edge");
    mo.band = g.positive("band", mo.band);
    if (spatial && g.has("offset"))
      g.fail("offset", "the eroded and dilated designs (an offset level set) are planar only");
    mo.offset = g.number("offset", mo.offset);
    g.finish();
    return entries;
  }

  void geometry(const JsonReader& g, Design& d) {
    const std::string body = g.string("body");
    if (spatial) {
      const SolidBody& sb =
          at_key(g, "body", [&]() -> const SolidBody& { return builder_.solid(body); });
      for (const auto& other : d.solid_bodies)
        if (other.body == &sb) g.fail("body", "body '" + sb.name + "' has two geometry entries");
      SolidGeometrySpec spec;
      const auto entries = geometry_spec(g, spec, [&](const JsonReader& f, bool& non_design) {
        return feature3(f, d, sb.mesh, non_design);
      });
      at_design(
          g, [&] { d.add_geometry(sb, std::move(spec)); }, &entries);
      return;
    }
    const FlexibleBody& fb =
        at_key(g, "body", [&]() -> const FlexibleBody& { return builder_.flexible(body); });
    for (const auto& other : d.bodies)
      if (other.body == &fb) g.fail("body", "body '" + fb.name + "' has two geometry entries");
    GeometrySpec spec;
    const auto entries = geometry_spec(
        g, spec, [&](const JsonReader& f, bool& non_design) { return feature(f, d, non_design); });
    at_design(
        g, [&] { d.add_geometry(fb, std::move(spec)); }, &entries);
  }

  void parameter_binding(const JsonReader& b, Design& d) {
    const std::string pname = b.string("parameter");
    const int parameter = builder_.parameter(pname);
    if (parameter < 0) {
      std::string avail;
      for (const auto& n : builder_.model().parameter_names())
        avail += (avail.empty() ? "" : ", ") + n;
      b.fail("parameter", "unknown model parameter '" + pname + "' (parameters: " + avail + ")");
    }
    const std::string vname = b.string("variable");
    if (d.variable_index(vname) < 0) b.fail("variable", "unknown design variable '" + vname + "'");
    const double scale = b.number("scale", 1.0), offset = b.number("offset", 0.0);
    b.finish();
    at_design(b, [&] { d.bind(parameter, vname, scale, offset, pname); });
  }

  void design(const JsonReader& r) {
    auto d = std::make_unique<Design>();
    for (const auto& v : r.items("variables", true)) variable(v, *d);
    if (d->variables.empty()) r.fail("variables", "expected at least one design variable");
    for (const auto& g : r.items("geometry")) geometry(g, *d);
    for (const auto& b : r.items("parameters")) parameter_binding(b, *d);
    r.finish();
    cs.design = std::move(d);
  }

  std::vector<std::pair<std::string, std::string>>
      pending_forces;  ///< constraint-force measures: name, joint
};

}  // namespace

namespace {

// One case, without service conditions (its document has none).
Case load_single(const nlohmann::json& j, const std::string& file_label,
                 const std::string& base_dir) {
  Case cs;
  cs.file = file_label;
  cs.base_dir = base_dir;
  cs.raw = j;
  Loader L(cs, base_dir);
  ModelBuilder& builder_ = L.builder_;
  const JsonReader root(j, file_label);
  if (!root.is_object()) root.fail("expected a JSON object at the top level");
  cs.name = root.string("name", fs::path(file_label).stem().string());
  const int dimension = root.integer("dimension", 2, 2);
  if (dimension > 3) root.fail("dimension", "expected 2 (planar) or 3 (spatial)");
  L.spatial = dimension == 3;
  if (root.has("gravity")) {
    if (L.spatial)
      builder_.set_spatial_gravity(root.vec3("gravity"));
    else
      builder_.set_gravity(root.vec2("gravity"));
  }
  const auto bodies = root.items("bodies", true);
  if (bodies.empty()) root.fail("bodies", "expected at least one body");
  for (const auto& b : bodies) {
    const std::string name = b.string("name");
    L.entry(b, name, true);
    if (L.spatial) {
      // flexible components of spatial mechanisms are solids: not yet
      if (b.has("type") && b.raw()["type"] == "flexible")
        b.fail("type",
               "plane-stress flexible bodies are planar; a flexible component of a spatial "
               "mechanism is a \"solid\" body (docs/case-format.md, \"Spatial cases\")");
      if (b.one_of("type", {"rigid", "solid"}) == "solid")
        L.solid_body(b, name);
      else
        L.spatial_body(b, name);
      continue;
    }
    const std::string type = b.one_of("type", {"rigid", "flexible"});
    if (type == "rigid")
      L.rigid_body(b, name);
    else
      L.flexible_body(b, name);
  }
  int i = 0;
  for (const auto& jt : root.items("joints")) L.kind_entry(jt, "joints", i++);
  i = 0;
  for (const auto& f : root.items("forces")) L.kind_entry(f, "forces", i++);
  if (auto d = root.optional_child("design")) L.design(*d);
  if (auto o = root.optional_child("optimization")) cs.optimization = o->raw();
  L.simulation(root.child("simulation"));
  if (auto out = root.optional_child("output")) {
    cs.output.csv_stride = out->integer("csv_stride", 1, 1);
    cs.output.vtu_stride = out->integer("vtu_stride", 0, 0);
    for (const auto& m : out->items("measures")) L.kind_entry(m, "measures", 0);
    for (const auto& r : out->items("responses")) L.response(r);
    out->finish();
  }
  const auto initial_state = root.optional_child("initial_state");
  if (initial_state && L.spatial)
    root.fail("initial_state",
              "not available in spatial cases yet (give velocities on the bodies)");
  root.finish();
  try {  // refuses undetermined bodies, numbers the constraint rows
    cs.model = builder_.build();
  } catch (const ModelError& e) {
    root.fail("bodies", e.message());
  }
  // constraint-force measures: rows are known now
  size_t pi = 0;
  for (auto& m : cs.measures) {
    if (m) continue;
    const auto& [nm, jn] = L.pending_forces[pi++];
    const std::vector<int>& rows = builder_.joint_rows(jn);
    std::vector<bool> angular;  // per row: an angle equation (a moment) or a length one (a force)
    const auto& cons = cs.model->constraints();
    for (int row : rows)
      for (size_t k = 0; k < cons.size(); ++k) {
        const int first = cs.model->constraint_offset(static_cast<int>(k));
        if (row >= first && row < first + cons[k]->size()) {
          angular.push_back(cons[k]->angular_equation(row - first));
          break;
        }
      }
    m = std::make_unique<ConstraintForceMeasure>(nm, rows, std::move(angular));
  }
  cs.joint_rows = builder_.joint_rows();
  for (const auto& [name, d] : builder_.drivers()) cs.drivers[name] = d.law;
  // what the start checks need from the builder, kept for the checks of a case changed later
  cs.start = builder_.start();
  cs.paths = L.paths;
  if (initial_state)
    read_initial_state(*initial_state, *cs.model, L.base_dir, cs.start, cs.paths,
                       cs.initial_state_note, L.files_read);
  prepare_case(cs);
  for (const auto& f : L.files_read) {  // the bytes each file held when the case was loaded
    std::ifstream in(f, std::ios::binary);
    if (!in) continue;
    std::stringstream ss;
    ss << in.rdbuf();
    cs.input_files[f] = sha256_hex(ss.str());
  }
  return cs;
}

// The top-level keys a condition may not change: the design, the optimization and the conditions
// themselves are one for all conditions.
bool condition_may_set(const std::string& first_token) {
  return first_token != "design" && first_token != "optimization" && first_token != "conditions" &&
         first_token != "combined" && first_token != "name" && first_token != "description";
}

// /design/geometry/<entry>/offset: the level set of a body offset (eroded or dilated design).
bool design_offset_pointer(const std::string& key) {
  const std::string head = "/design/geometry/", tail = "/offset";
  if (key.size() <= head.size() + tail.size() || key.rfind(head, 0) != 0) return false;
  if (key.compare(key.size() - tail.size(), tail.size(), tail) != 0) return false;
  const std::string entry = key.substr(head.size(), key.size() - head.size() - tail.size());
  return !entry.empty() && entry.find('/') == std::string::npos;
}

// "combined": [{"name", "aggregate": "sum" | "ks" | "max", "of": [names] or a response name
// (every condition's), "weights" (sum), "ks" (ks)}]
std::vector<ResponseCombination> read_combined(const JsonReader& root,
                                               const std::vector<std::string>& conditions) {
  std::vector<ResponseCombination> out;
  for (const auto& c : root.items("combined")) {
    ResponseCombination rc;
    rc.name = c.string("name");
    for (const auto& o : out)
      if (o.name == rc.name) c.fail("name", "duplicate combined response '" + rc.name + "'");
    const std::string agg = c.one_of("aggregate", {"sum", "ks", "max"});
    rc.kind = agg == "sum"  ? ResponseCombination::Kind::kSum
              : agg == "ks" ? ResponseCombination::Kind::kKs
                            : ResponseCombination::Kind::kMax;
    const JsonReader of = c.child("of");
    if (of.is_string()) {  // the response of that name in every condition
      for (const auto& k : conditions) rc.of.push_back(k + "." + of.as_string());
    } else if (of.is_array()) {
      for (size_t i = 0; i < of.size(); ++i) rc.of.push_back(of.at(i).as_string());
    } else {
      of.fail("expected a response name (that response of every condition) or a list of names");
    }
    if (rc.kind == ResponseCombination::Kind::kSum && c.has("weights")) {
      const JsonReader w = c.child("weights");
      if (!w.is_array()) w.fail("expected a list of numbers, one per response of \"of\"");
      for (size_t i = 0; i < w.size(); ++i) rc.weights.push_back(w.at(i).as_number());
    }
    if (rc.kind == ResponseCombination::Kind::kKs) rc.ks = c.positive("ks");
    c.finish();
    out.push_back(std::move(rc));
  }
  return out;
}

// A JSON pointer whose tokens may name an entry of an array of named entries
// (/forces/payload/mass): the same pointer with indices (/forces/2/mass). Error: which token.
std::string indexed_pointer_at(const nlohmann::json& doc, const std::string& pointer,
                               const JsonReader& at) {
  nlohmann::json::json_pointer ptr;
  try {
    ptr = nlohmann::json::json_pointer(pointer);
  } catch (const nlohmann::json::exception&) {
    at.fail("'" + pointer + "' is not a JSON pointer (expected /key/index/…, e.g. /simulation/h)");
  }
  std::vector<std::string> tokens;
  for (auto p = ptr; !p.empty(); p = p.parent_pointer()) tokens.insert(tokens.begin(), p.back());
  const nlohmann::json* node = &doc;
  std::string out;
  for (size_t i = 0; i < tokens.size(); ++i) {
    std::string t = tokens[i];
    if (node->is_array() && (t.empty() || t.find_first_not_of("0123456789") != std::string::npos)) {
      size_t found = node->size();
      for (size_t k = 0; k < node->size(); ++k)
        if ((*node)[k].is_object() && (*node)[k].value("name", "") == t) found = k;
      if (found == node->size())
        at.fail("'" + pointer + "': " + (out.empty() ? "/" : out) + " has no entry named '" + t +
                "'");
      t = std::to_string(found);
    }
    out += "/" + nlohmann::json::json_pointer(std::string("/") + t).back();
    const auto here = nlohmann::json::json_pointer(out);
    if (i + 1 < tokens.size()) {
      if (!doc.contains(here))
        at.fail("'" + pointer + "': the case has no " + out + " to set a value in");
      node = &doc.at(here);
    }
  }
  return out;
}

// One service condition: the base document with the condition's "set" applied, loaded as a case.
std::unique_ptr<Case> load_condition(const nlohmann::json& base, const JsonReader& c,
                                     const std::string& name, const std::string& file_label,
                                     const std::string& base_dir, std::vector<std::string>& sets) {
  nlohmann::json doc = base;
  std::vector<std::pair<std::string, std::string>> set;  // the case's pointer, as given
  if (auto s = c.optional_child("set")) {
    if (!s->is_object()) s->fail("expected {\"/json/pointer\": value, …}");
    for (const auto& [pointer, value] : s->raw().items()) {
      const std::string key = pointer;
      if (key.empty() || key[0] != '/')
        s->fail("'" + key + "': expected a JSON pointer into the case (/forces/payload/mass)");
      const std::string first = key.substr(1, key.find('/', 1) - 1);
      if (first == "design" && design_offset_pointer(key)) {
        // the one value of the design a condition may set: a variant of the design (robust
        // formulation), the same variables
      } else if (!condition_may_set(first))
        s->fail(key, "a condition changes the model, its loads, options and outputs; /" + first +
                         " is one for all conditions" +
                         (first == "design" ? std::string(" (of the design it may set only "
                                                          "/design/geometry/<entry>/offset: an "
                                                          "eroded or dilated variant)")
                                            : std::string()));
      const std::string indexed = indexed_pointer_at(doc, key, *s);
      doc[nlohmann::json::json_pointer(indexed)] = value;
      set.emplace_back(indexed, key);
      sets.push_back(indexed);
    }
  }
  try {
    auto ck = std::make_unique<Case>(load_single(doc, file_label, base_dir));
    ck->name = name;
    return ck;
  } catch (const Error& e) {  // where in the condition's document, and which value it set
    std::string reason = e.what();
    for (const std::string& part : {e.file(), e.json_path()})
      if (!part.empty() && reason.rfind(part + ": ", 0) == 0) reason.erase(0, part.size() + 2);
    std::string by;
    for (const auto& [indexed, given] : set)
      if (e.json_path() == indexed || e.json_path().rfind(indexed + "/", 0) == 0)
        by = ", set by the condition as " + given;
    c.fail("condition '" + name + "': " + e.json_path() + ": " + reason + by);
  }
}

}  // namespace

Case load_case_json(const nlohmann::json& j, const std::string& file_label,
                    const std::string& base_dir) {
  if (!j.is_object() || (!j.contains("conditions") && !j.contains("combined")))
    return load_single(j, file_label, base_dir);
  nlohmann::json base = j;
  base.erase("conditions");
  base.erase("combined");
  Case cs = load_single(base, file_label, base_dir);
  cs.raw = j;
  const JsonReader root(j, file_label);
  std::vector<std::string> names;
  for (const auto& c : root.items("conditions")) {
    const std::string name = c.string("name");
    if (name.empty() || name.find('.') != std::string::npos)
      c.fail("name", "expected a name without '.' (responses are named <condition>.<response>)");
    if (std::find(names.begin(), names.end(), name) != names.end())
      c.fail("name", "duplicate condition '" + name + "'");
    names.push_back(name);
    CaseCondition k;
    k.name = name;
    k.cs = load_condition(base, c, name, file_label, base_dir, k.set);
    c.finish();
    for (const auto& [f, sha] : k.cs->input_files) cs.input_files[f] = sha;
    // a response that does not depend on the motion (a mass) is evaluated once, in the first
    // condition (Conditions::reported)
    // … except in a variant of the design (a condition that sets /design/…/offset), whose mass is
    // its own
    const bool variant = is_design_variant(k);
    bool plain_before = false;
    for (const auto& e : cs.conditions) plain_before |= !is_design_variant(e);
    if (!variant && plain_before) {
      std::vector<ResponseSpec> kept;
      for (size_t r = 0; r < k.cs->responses.size(); ++r)
        if (!Conditions::state_independent(*k.cs, r)) kept.push_back(k.cs->responses[r]);
      k.cs->responses = std::move(kept);
    }
    cs.conditions.push_back(std::move(k));
  }
  if (root.has("conditions") && cs.conditions.empty())
    root.fail("conditions", "expected at least one condition (or no \"conditions\" key)");
  cs.combined = read_combined(root, names);
  try {
    conditions_of(cs).validate();
  } catch (const SetupError& e) {
    for (size_t i = 0; i < cs.combined.size(); ++i)
      if (cs.combined[i].name == e.entity())
        throw Error(file_label, "/combined/" + std::to_string(i), e.reason());
    throw;
  }
  return cs;
}

std::string indexed_pointer(const nlohmann::json& doc, const std::string& pointer,
                            const std::string& what) {
  const nlohmann::json empty = nlohmann::json::object();
  const JsonReader at(empty, what);
  return indexed_pointer_at(doc, pointer, at);
}

nlohmann::json current_document(const Case& cs) {
  nlohmann::json doc = cs.raw;
  const nlohmann::json simulation = cs.simulation;  // named: items() refers to it
  for (const auto& [key, value] : simulation.items())
    doc["simulation"][key] = value;  // every option, as the case holds it now
  const auto& names = cs.model->parameter_names();
  for (size_t i = 0; i < names.size(); ++i) {
    bool bound = false;
    if (cs.design)
      for (const auto& b : cs.design->bindings) bound |= b.parameter == static_cast<int>(i);
    const std::string path = parameter_json_path(cs, static_cast<int>(i));
    if (bound || path.empty()) continue;
    const auto ptr = nlohmann::json::json_pointer(path);
    if (doc.contains(ptr.parent_pointer())) doc[ptr] = cs.model->params().scalars[i];
  }
  return doc;
}

bool is_design_variant(const CaseCondition& c) {
  for (const auto& s : c.set)
    if (s.rfind("/design/", 0) == 0) return true;
  return false;
}

Conditions conditions_of(const Case& cs) {
  if (cs.conditions.empty()) {
    Conditions c = Conditions::single(cs);
    c.combinations = cs.combined;
    return c;
  }
  Conditions c;
  for (const auto& k : cs.conditions) {
    c.names.push_back(k.name);
    c.studies.push_back(k.cs.get());
    c.design_variant.push_back(is_design_variant(k) ? 1 : 0);
  }
  c.combinations = cs.combined;
  return c;
}

Case load_case(const std::string& path) { return load_case(path, {}); }

Case load_case(const std::string& path, const std::vector<CaseOverride>& overrides) {
  if (const auto why = unreadable_file_reason(path); !why.empty())
    throw Error(path, "", "case file: " + why);
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path, "", "cannot open case file");
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str();
  nlohmann::json j;
  try {
    j = parse_json_document(text, path);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(path, "byte " + std::to_string(e.byte), std::string("invalid JSON: ") + e.what());
  } catch (const nlohmann::json::exception&
               e) {  // e.g. out_of_range: a number like 1e999 (found by fuzzing)
    throw Error(path, "", std::string("invalid JSON: ") + e.what());
  }
  nlohmann::json applied = nlohmann::json::object();
  for (const auto& o : overrides) {
    nlohmann::json::json_pointer ptr;
    try {
      ptr = nlohmann::json::json_pointer(o.pointer);
    } catch (const nlohmann::json::exception&) {
      throw Error(o.origin + ": '" + o.pointer +
                  "' is not a JSON pointer (expected /key/index/…, e.g. /simulation/h)");
    }
    if (ptr.empty())
      throw Error(o.origin + ": expected a path below the document, e.g. /simulation/h");
    const auto parent = ptr.parent_pointer();
    if (!j.contains(parent))
      throw Error(path, parent.to_string(),
                  o.origin + ": the case has no " + parent.to_string() + " to set a value in");
    const nlohmann::json& holder = j.at(parent);
    if (holder.is_array()) {
      const std::string& key = ptr.back();
      // an index as JSON pointers spell it: digits, no leading zero ("01" is not 1)
      const bool index = !key.empty() && key.find_first_not_of("0123456789") == std::string::npos &&
                         (key == "0" || key[0] != '0');
      if (!index || key.size() > 9 || std::stoul(key) >= holder.size())
        throw Error(path, o.pointer,
                    o.origin + ": " + parent.to_string() + " is an array of " +
                        std::to_string(holder.size()) + " entries; expected an index below " +
                        std::to_string(holder.size()));
    } else if (!holder.is_object()) {
      throw Error(path, parent.to_string(),
                  o.origin + ": " + parent.to_string() + " holds a " + holder.type_name() +
                      ", not an object or array");
    }
    j[ptr] = o.value;
    applied[o.pointer] = o.value;
  }
  try {
    Case cs = load_case_json(j, path, fs::path(path).parent_path().string());
    cs.sha256 = sha256_hex(text);
    cs.overrides = std::move(applied);
    return cs;
  } catch (const Error& e) {  // an error at an overridden value names the override
    for (const auto& o : overrides) {
      const std::string& at = e.json_path();
      if (!at.empty() && (at == o.pointer || at.rfind(o.pointer + "/", 0) == 0 ||
                          o.pointer.rfind(at + "/", 0) == 0)) {
        std::string reason = e.what();  // without the "file: path: " prefix
        for (const std::string& part : {e.file(), at})
          if (!part.empty() && reason.rfind(part + ": ", 0) == 0) reason.erase(0, part.size() + 2);
        throw Error(e.file(), at, reason + " (the value was set by " + o.origin + ")");
      }
    }
    throw;
  }
}

}  // namespace lsmbs
