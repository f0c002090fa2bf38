// ModelBuilder: named entities to elements (the conventions are listed in model_builder.hpp and
// docs/library.md). Every call checks its arguments before it changes the model.
#include "lsmbs/mbs/model_builder.hpp"

#include <cmath>
#include <stdexcept>

namespace lsmbs {

ModelBuilder::ModelBuilder() : model_(std::make_unique<Model>()), m_(model_.get()) {}

void ModelBuilder::set_gravity(const Vec2& g) {
  check_not_built();
  m_->params().gravity = g;
}

// ---------------------------------------------------------------- helpers

void ModelBuilder::fail(const Entity& e, const std::string& field, const std::string& what) {
  throw ModelError(e.kind.empty() ? std::string() : e.kind + " '" + e.name + "'", field, what);
}

// An options struct's validate() message "field: what" as the entity's ModelError.
void ModelBuilder::check(const Entity& e, const std::string& validation) {
  if (validation.empty()) return;
  const auto colon = validation.find(": ");
  fail(e, validation.substr(0, colon), validation.substr(colon + 2));
}

std::string RigidBodyOptions::validate() const {
  if (!(mass >= 0)) return "mass: expected a non-negative mass";
  if (!(inertia >= 0)) return "inertia: expected a non-negative inertia";
  return {};
}

std::string FlexibleBodyOptions::validate() const {
  if (!(E > 0)) return "material/E: expected a positive Young's modulus";
  if (!(nu >= 0 && nu < 0.5)) return "material/nu: expected Poisson's ratio in [0, 0.5)";
  if (!(rho > 0)) return "material/rho: expected a positive density";
  if (!(thickness > 0)) return "thickness: expected a positive thickness";
  return {};
}

std::string PrismaticOptions::validate() const {
  if (through && !through->allFinite()) return "through: expected a finite point";
  return {};
}

std::string SpringOptions::validate() const {
  if (!(stiffness >= 0)) return "stiffness: expected a non-negative stiffness";
  if (!(damping >= 0)) return "damping: expected a non-negative damping";
  if (free_length && !(*free_length >= 0))
    return "free_length: expected a non-negative free length";
  return {};
}

std::string RotationalSpringOptions::validate() const {
  if (!(stiffness >= 0)) return "stiffness: expected a non-negative stiffness";
  if (!(damping >= 0)) return "damping: expected a non-negative damping";
  return {};
}

void ModelBuilder::check_not_built() const {
  if (built_)
    throw std::logic_error("ModelBuilder: the model was built already (nothing can be added)");
  if (broken_)
    throw std::logic_error(
        "ModelBuilder: a flexible body's mesh was refused and the model holds part of it; "
        "start a new builder");
}

void ModelBuilder::check_name(const Entity& e, bool body) const {
  if (names_.count(e.name))
    fail(e, "name",
         "duplicate name '" + e.name + "' (bodies, joints and forces need unique names)");
  if (body && e.name == "ground") fail(e, "name", "'ground' is reserved");
}

void ModelBuilder::check_name(const std::string& name, bool body) const {
  check_name({"", name}, body);
}

ModelBuilder::Mark ModelBuilder::begin(const Entity& e) const {
  check_not_built();
  check_name(e, e.kind == "rigid body" || e.kind == "flexible body" || e.kind == "spatial body");
  return {m_->forces().size(), m_->constraints().size()};
}

void ModelBuilder::commit(const Entity& e, const Mark& mark) {
  names_.insert(e.name);
  if (m_->forces().size() > mark.force) force_owners_.emplace_back(mark.force, e.name);
  if (e.kind == "joint") joint_elements_[e.name] = {mark.constraint, m_->constraints().size()};
}

int ModelBuilder::param(const Entity& e, const std::string& property, double value) {
  const int i = m_->add_parameter(e.name + "." + property, value);
  entity_params_[e.name].push_back(i);
  return i;
}

std::vector<int> ModelBuilder::parameters_of(const std::string& entity) const {
  auto it = entity_params_.find(entity);
  return it == entity_params_.end() ? std::vector<int>{} : it->second;
}

void ModelBuilder::add_constraint(const Entity& e, std::unique_ptr<ConstraintElement> c) {
  c->set_name(e.name);
  m_->add_constraint(std::move(c));
}

ModelBuilder::BodyKind ModelBuilder::body_kind(const std::string& name) const {
  if (m_->find_rigid(name)) return BodyKind::kRigid;
  if (m_->find_flexible(name)) return BodyKind::kFlexible;
  if (m_->find_spatial(name)) return BodyKind::kSpatial;
  return BodyKind::kNone;
}

const RigidBody& ModelBuilder::rigid(const Entity& e, const std::string& field,
                                     const std::string& name) const {
  const RigidBody* b = m_->find_rigid(name);
  if (!b) {
    if (m_->find_flexible(name))
      fail(e, field, "'" + name + "' is a flexible body; a rigid body is expected here");
    fail(e, field, "unknown rigid body '" + name + "'");
  }
  return *b;
}

const FlexibleBody& ModelBuilder::flexible(const Entity& e, const std::string& field,
                                           const std::string& name) const {
  const FlexibleBody* b = m_->find_flexible(name);
  if (!b) {
    if (m_->find_rigid(name))
      fail(e, field, "'" + name + "' is a rigid body; a flexible body is expected here");
    fail(e, field, "unknown flexible body '" + name + "'");
  }
  return *b;
}

const RigidBody& ModelBuilder::rigid(const std::string& name) const { return rigid({}, "", name); }
const FlexibleBody& ModelBuilder::flexible(const std::string& name) const {
  return flexible({}, "", name);
}
int ModelBuilder::angle_dof(const std::string& rigid_body) const {
  return rigid(rigid_body).dof0 + 2;
}

const std::vector<int>& ModelBuilder::node_set(const Entity& e, const std::string& field,
                                               const FlexibleBody& b,
                                               const std::string& set) const {
  auto it = b.mesh.node_sets.find(set);
  if (it == b.mesh.node_sets.end()) {
    std::string avail;
    for (const auto& [k, v] : b.mesh.node_sets) avail += (avail.empty() ? "" : ", ") + k;
    fail(e, field,
         "body '" + b.name + "' has no node set '" + set + "' (available: " + avail + ")");
  }
  return it->second;
}

// ---------------------------------------------------------------- points

PointRef ModelBuilder::resolve(const Point& p) const { return resolve({}, "", p); }

// Errors name "<field>/body" or "<field>/node": the keys of a point in the case format.
PointRef ModelBuilder::resolve(const Entity& e, const std::string& field, const Point& p) const {
  const std::string at = field.empty() ? "" : field + "/";
  PointRef r;
  if (p.kind == Point::Kind::kGround) {
    r.kind = PointRef::Kind::kGround;
    r.local = p.x;
    return r;
  }
  if (const RigidBody* rb = m_->find_rigid(p.body)) {
    if (p.kind == Point::Kind::kNode || p.kind == Point::Kind::kNearest)
      fail(e, at + "body", "'" + p.body + "' is a rigid body; a node needs a flexible body");
    r.kind = PointRef::Kind::kBody;
    r.dof0 = rb->dof0;
    // a point given by its position at t = 0 keeps that position's offset in the body frame
    if (p.kind == Point::Kind::kGlobal)
      r.local = rotation(rb->angle0).transpose() * (p.x - rb->position0);
    else
      r.local = p.x;
  } else if (const FlexibleBody* fb = m_->find_flexible(p.body)) {
    int node = -1;
    if (p.kind == Point::Kind::kNode) {
      node = p.index;
      if (node < 0 || node >= fb->mesh.num_nodes())
        fail(e, at + "node",
             "node index " + std::to_string(node) + " out of range (body '" + p.body + "' has " +
                 std::to_string(fb->mesh.num_nodes()) + " nodes)");
    } else if (p.kind == Point::Kind::kNearest) {
      node = fb->mesh.nearest_node(p.x);
    } else {
      fail(e, at + "body",
           "'" + p.body +
               "' is a flexible body; a point on it is a node (Point::node or Point::nearest)");
    }
    r.kind = PointRef::Kind::kNode;
    r.dof0 = fb->node_dof(node);
  } else {
    fail(e, at + "body", "unknown body '" + p.body + "'");
  }
  return r;
}

Vec2 ModelBuilder::initial_position(const Point& p) const { return initial_position(resolve(p)); }

Vec2 ModelBuilder::initial_position(const PointRef& p) const {
  if (p.kind == PointRef::Kind::kGround) return p.local;
  const Vec q = m_->initial_positions();
  double b[3] = {q[p.dof0], q[p.dof0 + 1], p.kind == PointRef::Kind::kBody ? q[p.dof0 + 2] : 0};
  return PointKinematics::position(p, b);
}

// ---------------------------------------------------------------- bodies

void ModelBuilder::given_velocity(const std::string& body, int first, int rotation_dof,
                                  bool translation, bool rotation, const std::string& field) {
  const int end = m_->nq();
  held_v_.resize(end, 0);
  for (int i = first; i < end; ++i) held_v_[i] = i < rotation_dof ? translation : rotation;
  if (translation || rotation) given_v_.push_back({body, field, first, end});
}

void ModelBuilder::rigid_body(const std::string& name, const RigidBodyOptions& o) {
  const Entity e{"rigid body", name};
  const Mark mark = begin(e);
  check(e, o.validate());
  RigidBody b;
  b.name = name;
  b.position0 = o.position;
  b.angle0 = o.angle;
  b.com_offset = o.com;
  b.mass_param = param(e, "mass", o.mass);
  b.inertia_param = param(e, "inertia", o.inertia);
  const RigidBody& rb = m_->add_rigid_body(b);
  // inertia of the body about its reference point: mass at the body-frame offset c, J_c about it
  m_->add_force(std::make_unique<RigidInertia>(rb.dof0, rb.mass_param, rb.inertia_param,
                                               rb.com_offset, "rigid body '" + name + "'"));
  const Vec2 v0 = o.velocity.value_or(Vec2::Zero());
  init_v_.conservativeResize(m_->nq());
  init_v_.segment<3>(rb.dof0) << v0.x(), v0.y(), o.angular_velocity.value_or(0.0);
  given_velocity(name, rb.dof0, rb.dof0 + 2, o.velocity.has_value(), o.angular_velocity.has_value(),
                 o.velocity ? "velocity" : "angular_velocity");
  commit(e, mark);
}

void ModelBuilder::flexible_body(const std::string& name, Mesh2D mesh,
                                 const FlexibleBodyOptions& o) {
  const Entity e{"flexible body", name};
  const Mark mark = begin(e);
  check(e, o.validate());
  for (const auto& [set, nodes] : mesh.node_sets) {
    if (nodes.empty()) fail(e, "node_sets/" + set, "node set '" + set + "' is empty");
    for (int n : nodes)
      if (n < 0 || n >= mesh.num_nodes())
        fail(e, "node_sets/" + set,
             "node set '" + set + "' holds node index " + std::to_string(n) + " (the mesh has " +
                 std::to_string(mesh.num_nodes()) + " nodes)");
  }
  FlexibleBody b;
  b.name = name;
  b.mesh = std::move(mesh);
  b.origin = o.origin;
  b.angle = o.angle;
  b.E_param = param(e, "E", o.E);
  b.nu_param = param(e, "nu", o.nu);
  b.rho_param = param(e, "rho", o.rho);
  b.thickness_param = param(e, "thickness", o.thickness);
  b.element_options.full_integration = o.full_integration;
  const FlexibleBody* added = nullptr;
  try {  // the element geometry is checked here (inverted or degenerate quadrilaterals)
    added = &m_->add_flexible_body(std::move(b));
  } catch (const Error& err) {  // the model holds the body's unknowns already: the builder is spent
    broken_ = true;
    fail(e, "mesh", err.what());
  }
  const FlexibleBody& fb = *added;
  // the rigid velocity field v + ω × (x − origin) at the placed nodes
  const Vec2 v0 = o.velocity.value_or(Vec2::Zero());
  const double w0 = o.angular_velocity.value_or(0.0);
  init_v_.conservativeResize(m_->nq());
  for (int i = 0; i < fb.mesh.num_nodes(); ++i) {
    const Vec2 x = fb.placed(i) - fb.origin;
    init_v_.segment<2>(fb.node_dof(i)) = v0 + w0 * Vec2(-x.y(), x.x());
  }
  const bool given = o.velocity || o.angular_velocity;  // the whole rigid field
  given_velocity(name, fb.node_dof(0), m_->nq(), given, given,
                 o.velocity ? "velocity" : "angular_velocity");
  commit(e, mark);
}

// ---------------------------------------------------------------- joints and drivers

void ModelBuilder::revolute(const std::string& name, const Point& a,
                            const std::optional<Point>& b) {
  const Entity e{"joint", name};
  const Mark mark = begin(e);
  const PointRef pa = resolve(e, "a", a);
  PointRef pb;
  if (b)
    pb = resolve(e, "b", *b);
  else
    pb = {PointRef::Kind::kGround, -1, initial_position(pa)};  // the pin where a is at t = 0
  if (pa.kind == PointRef::Kind::kGround && pb.kind == PointRef::Kind::kGround)
    fail(e, "", "both points are ground");
  add_constraint(e, std::make_unique<PointCoincidence>(pa, pb));
  m_->add_attachment(pa);
  m_->add_attachment(pb);
  commit(e, mark);
}

void ModelBuilder::prismatic(const std::string& name, const Point& a, const Vec2& direction,
                             const PrismaticOptions& o) {
  const Entity e{"joint", name};
  const Mark mark = begin(e);
  const PointRef pa = resolve(e, "a", a);
  if (pa.kind == PointRef::Kind::kGround) fail(e, "a", "the sliding point must be on a body");
  if (!(direction.norm() > 0)) fail(e, "direction", "expected a non-zero direction");
  check(e, o.validate());
  const Vec2 x0 = o.through.value_or(initial_position(pa));
  // the rotation lock keeps the body's initial angle (a node has no angle: nothing to lock)
  double th0 = 0;
  if (pa.kind == PointRef::Kind::kBody) th0 = m_->initial_positions()[pa.dof0 + 2];
  add_constraint(e, std::make_unique<Prismatic>(pa, x0, direction, o.lock_rotation, th0));
  m_->add_attachment(pa);
  commit(e, mark);
}

void ModelBuilder::rigid_connection(const std::string& name, const std::string& rigid_body,
                                    const std::string& flexible_body, const std::string& set) {
  const Entity e{"joint", name};
  const Mark mark = begin(e);
  const RigidBody& rb = rigid(e, "rigid", rigid_body);
  const FlexibleBody& fb = flexible(e, "flexible", flexible_body);
  for (int nd : node_set(e, "node_set", fb, set)) {
    // the node's initial offset in the rigid body's frame: d = R(θ0)ᵀ (x_node − x0)
    const Vec2 off = rotation(rb.angle0).transpose() * (fb.placed(nd) - rb.position0);
    add_constraint(e, std::make_unique<PointCoincidence>(
                          PointRef{PointRef::Kind::kNode, fb.node_dof(nd), Vec2::Zero()},
                          PointRef{PointRef::Kind::kBody, rb.dof0, off}));
    m_->add_attachment(PointRef{PointRef::Kind::kBody, rb.dof0, off});
  }
  commit(e, mark);
}

void ModelBuilder::clamp(const std::string& name, const std::string& flexible_body,
                         const std::string& set) {
  const Entity e{"joint", name};
  const Mark mark = begin(e);
  const FlexibleBody& fb = flexible(e, "flexible", flexible_body);
  for (int nd : node_set(e, "node_set", fb, set))
    add_constraint(e, std::make_unique<PointCoincidence>(
                          PointRef{PointRef::Kind::kNode, fb.node_dof(nd), Vec2::Zero()},
                          PointRef{PointRef::Kind::kGround, -1, fb.placed(nd)}));
  commit(e, mark);
}

void ModelBuilder::rotation_driver(const std::string& name, const std::string& body,
                                   std::shared_ptr<const TimeLaw> law,
                                   const std::string& relative_to) {
  const Entity e{"joint", name};
  const Mark mark = begin(e);
  const RigidBody& b = rigid(e, "body", body);
  int a_dof = -1;
  if (relative_to != "ground") {
    const RigidBody* a = m_->find_rigid(relative_to);
    if (!a) fail(e, "relative_to", "unknown rigid body '" + relative_to + "' (or \"ground\")");
    if (a == &b) fail(e, "relative_to", "a body cannot be driven relative to itself");
    a_dof = a->dof0 + 2;
  }
  if (!law) fail(e, "law", "expected a law");
  drivers_[name] = {law, a_dof >= 0};
  add_constraint(e, std::make_unique<AngleDriver>(a_dof, b.dof0 + 2, std::move(law)));
  commit(e, mark);
}

void ModelBuilder::translation_driver(const std::string& name, const Point& point,
                                      const Vec2& direction, std::shared_ptr<const TimeLaw> law,
                                      const std::optional<Vec2>& through) {
  const Entity e{"joint", name};
  const Mark mark = begin(e);
  const PointRef p = resolve(e, "point", point);
  if (!(direction.norm() > 0)) fail(e, "direction", "expected a non-zero direction");
  const Vec2 x0 = through.value_or(initial_position(p));
  if (!law) fail(e, "law", "expected a law");
  drivers_[name] = {law, false};
  add_constraint(e, std::make_unique<TranslationDriver>(p, x0, direction, std::move(law)));
  m_->add_attachment(p);
  commit(e, mark);
}

// ---------------------------------------------------------------- forces

void ModelBuilder::point_mass(const std::string& name, const Point& point, double mass) {
  const Entity e{"point mass", name};
  const Mark mark = begin(e);
  if (!(mass >= 0)) fail(e, "mass", "expected a non-negative mass");
  const PointRef p = resolve(e, "point", point);
  if (p.kind == PointRef::Kind::kGround) fail(e, "point", "a point mass must sit on a body");
  const int mp = param(e, "mass", mass);
  // on a node: a lumped nodal mass; on a rigid body: a mass at its body-frame offset, J_c = 0
  if (p.kind == PointRef::Kind::kNode)
    m_->add_force(std::make_unique<NodeMass>(p.dof0, mp, "point mass '" + name + "'"));
  else
    m_->add_force(
        std::make_unique<RigidInertia>(p.dof0, mp, -1, p.local, "point mass '" + name + "'"));
  m_->add_attachment(p);
  commit(e, mark);
}

void ModelBuilder::point_force(const std::string& name, const Point& point,
                               std::shared_ptr<const TimeLaw> fx, std::shared_ptr<const TimeLaw> fy,
                               double scale) {
  const Entity e{"force", name};
  const Mark mark = begin(e);
  const PointRef p = resolve(e, "point", point);
  if (p.kind == PointRef::Kind::kGround) fail(e, "point", "a force must act on a body");
  if (!fx) fx = std::make_shared<ConstantLaw>(0.0);
  if (!fy) fy = std::make_shared<ConstantLaw>(0.0);
  const int sp = param(e, "scale", scale);
  m_->add_force(
      std::make_unique<PointForce>(p, std::move(fx), std::move(fy), sp, "force '" + name + "'"));
  m_->add_attachment(p);
  commit(e, mark);
}

void ModelBuilder::point_force(const std::string& name, const Point& point, const Vec2& force,
                               double scale) {
  point_force(name, point, std::make_shared<ConstantLaw>(force.x()),
              std::make_shared<ConstantLaw>(force.y()), scale);
}

void ModelBuilder::spring_damper(const std::string& name, const Point& a, const Point& b,
                                 const SpringOptions& o) {
  const Entity e{"spring", name};
  const Mark mark = begin(e);
  const PointRef pa = resolve(e, "a", a), pb = resolve(e, "b", b);
  check(e, o.validate());
  // the free length defaults to the initial distance: the spring is unloaded at t = 0
  const double l_init = (initial_position(pb) - initial_position(pa)).norm();
  if (!(l_init > 0))
    fail(e, "", "the spring's end points coincide initially (direction undefined)");
  const int kp = param(e, "stiffness", o.stiffness);
  const int cp = param(e, "damping", o.damping);
  const int lp = param(e, "free_length", o.free_length.value_or(l_init));
  m_->add_force(std::make_unique<SpringDamper>(pa, pb, kp, cp, lp, "spring '" + name + "'"));
  m_->add_attachment(pa);
  m_->add_attachment(pb);
  commit(e, mark);
}

void ModelBuilder::torque(const std::string& name, const std::string& body,
                          std::shared_ptr<const TimeLaw> law, double scale) {
  const Entity e{"torque", name};
  const Mark mark = begin(e);
  const RigidBody& b = rigid(e, "body", body);
  if (!law) fail(e, "law", "expected a law");
  const int sp = param(e, "scale", scale);
  m_->add_force(std::make_unique<Torque>(b.dof0 + 2, std::move(law), sp, "torque '" + name + "'"));
  commit(e, mark);
}

void ModelBuilder::torque(const std::string& name, const std::string& body, double torque,
                          double scale) {
  this->torque(name, body, std::make_shared<ConstantLaw>(torque), scale);
}

void ModelBuilder::rotational_spring_damper(const std::string& name, const std::string& a,
                                            const std::string& b,
                                            const RotationalSpringOptions& o) {
  const Entity e{"rotational spring", name};
  const Mark mark = begin(e);
  const RigidBody& ra = rigid(e, "a", a);
  int b_dof = -1;
  double th_b = 0;  // θ_ground = 0
  if (b != "ground") {
    const RigidBody& rb = rigid(e, "b", b);
    if (&rb == &ra) fail(e, "b", "a rotational spring cannot connect a body to itself");
    b_dof = rb.dof0 + 2;
    th_b = rb.angle0;
  }
  check(e, o.validate());
  const int kp = param(e, "stiffness", o.stiffness);
  const int cp = param(e, "damping", o.damping);
  // the free angle defaults to the initial relative angle: no moment at t = 0
  const int tp = param(e, "free_angle", o.free_angle.value_or(ra.angle0 - th_b));
  m_->add_force(std::make_unique<RotationalSpringDamper>(ra.dof0 + 2, b_dof, kp, cp, tp,
                                                         "rotational spring '" + name + "'"));
  commit(e, mark);
}

void ModelBuilder::pressure(const std::string& name, const Point& point, const Vec2& direction,
                            double area, Table1D table, const PressureArgument& argument) {
  const Entity e{"pressure", name};
  const Mark mark = begin(e);
  const PointRef p = resolve(e, "point", point);
  if (p.kind == PointRef::Kind::kGround) fail(e, "point", "a pressure force must act on a body");
  if (!(direction.norm() > 0)) fail(e, "direction", "expected a non-zero direction");
  if (!(area > 0)) fail(e, "area", "expected a positive area");
  // the table's argument: the time, or the angle θ of a rigid body (the load then enters K_t)
  const int angle_dof =
      argument.angle_of.empty() ? -1 : rigid(e, "argument/angle_of", argument.angle_of).dof0 + 2;
  const int ap = param(e, "area", area);
  m_->add_force(std::make_unique<PressureForce>(p, direction, ap, std::move(table), angle_dof,
                                                argument.offset, "pressure '" + name + "'"));
  m_->add_attachment(p);
  commit(e, mark);
}

// ---------------------------------------------------------------- queries

const DriverInfo* ModelBuilder::driver(const std::string& name) const {
  auto it = drivers_.find(name);
  return it == drivers_.end() ? nullptr : &it->second;
}

int ModelBuilder::joint_equations(const std::string& joint) const {
  auto it = joint_elements_.find(joint);
  if (it == joint_elements_.end()) throw ModelError("", "", "unknown joint '" + joint + "'");
  int m = 0;
  for (size_t k = it->second.first; k < it->second.second; ++k) m += m_->constraints()[k]->size();
  return m;
}

const std::string& ModelBuilder::force_owner(size_t f) const {
  static const std::string none;
  const std::string* owner = &none;
  for (const auto& [first, name] : force_owners_)
    if (first <= f) owner = &name;
  return *owner;
}

// ---------------------------------------------------------------- build

// Rigid bodies that no constraint, mass or inertia touches would make the iteration matrix
// singular; they are reported by name before any run.
void ModelBuilder::check_determined() const {
  std::vector<char> touched(m_->nq(), 0);
  for (const auto& c : m_->constraints())
    for (int d : c->dofs()) touched[d] = 1;
  for (const auto& b : m_->rigid_bodies()) {
    const double mass = m_->params().scalars[b.mass_param],
                 J = m_->params().scalars[b.inertia_param];
    const bool constrained = touched[b.dof0] || touched[b.dof0 + 1] || touched[b.dof0 + 2];
    if (!constrained && mass == 0 && J == 0)
      fail({"rigid body", b.name}, "",
           "rigid body '" + b.name + "' has no mass and no joint: its motion is not determined");
  }
  for (const auto& b : m_->spatial_bodies()) {
    double inertia = m_->params().scalars[static_cast<size_t>(b.mass_param)];
    for (int ip : b.inertia_params) inertia += m_->params().scalars[static_cast<size_t>(ip)];
    bool constrained = false;  // by more than its own frame constraints
    for (const auto& c : m_->constraints())
      if (c->name() != b.name + ".frame")
        for (int d : c->dofs()) constrained = constrained || (d >= b.dof0 && d < b.dof0 + 12);
    if (!constrained && inertia == 0)
      fail({"spatial body", b.name}, "",
           "spatial body '" + b.name + "' has no mass and no joint: its motion is not determined");
  }
}

std::unique_ptr<Model> ModelBuilder::build() {
  check_not_built();
  check_determined();
  m_->finalize();
  for (const auto& [name, range] : joint_elements_) {
    std::vector<int> rows;
    for (size_t k = range.first; k < range.second; ++k)
      for (int r = 0; r < m_->constraints()[k]->size(); ++r)
        rows.push_back(m_->constraint_offset(static_cast<int>(k)) + r);
    joint_rows_[name] = std::move(rows);
  }
  initial_.t = 0;
  initial_.q = m_->initial_positions();
  initial_.v = init_v_;
  initial_.v.conservativeResize(m_->nq());
  initial_.a.setZero(m_->nq());
  initial_.lambda.setZero(m_->nc());
  held_v_.resize(m_->nq(), 0);
  built_ = true;
  return std::move(model_);
}

ModelStart ModelBuilder::start() const {
  ModelStart st;
  st.placed = initial_state();
  st.held_velocities = held_velocities();
  st.given_velocities = given_velocities();
  for (size_t f = 0; f < m_->forces().size(); ++f) st.force_owners.push_back(force_owner(f));
  for (const auto& [name, params] : entity_params_)
    if (!params.empty()) st.entity_parameters[name] = params;
  return st;
}

const State& ModelBuilder::initial_state() const {
  if (!built_) throw std::logic_error("ModelBuilder::initial_state before build()");
  return initial_;
}

const std::vector<int>& ModelBuilder::joint_rows(const std::string& joint) const {
  if (!built_) throw std::logic_error("ModelBuilder::joint_rows before build()");
  auto it = joint_rows_.find(joint);
  if (it == joint_rows_.end()) throw ModelError("", "", "unknown joint '" + joint + "'");
  return it->second;
}

std::string ModelBuilder::check_parameter_value(const std::string& name, double v) {
  // the case loader's words for the same value in a case file (io/json_reader.cpp)
  if (!std::isfinite(v)) return "expected a finite number";
  const std::string prop = name.substr(name.rfind('.') + 1);
  if ((prop == "E" || prop == "rho" || prop == "thickness" || prop == "area") && !(v > 0))
    return "expected a positive number";
  if (prop == "nu" && !(v >= 0 && v < 0.5)) return "expected Poisson's ratio in [0, 0.5)";
  if ((prop == "mass" || prop == "inertia" || prop == "stiffness" || prop == "damping" ||
       prop == "free_length") &&
      !(v >= 0))
    return "expected a non-negative number";
  return {};
}

}  // namespace lsmbs
