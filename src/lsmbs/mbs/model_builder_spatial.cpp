// The spatial part of ModelBuilder (model_builder.hpp): bodies in natural coordinates, joints,
// drivers, loads and spring–dampers of mbs/spatial*.hpp, named like the planar ones.
#include <cmath>
#include <cstdio>
#include <map>

#include "lsmbs/mbs/model_builder.hpp"

namespace lsmbs {

namespace {

bool finite(const Vec3& v) { return v.allFinite(); }

const char* joint_kind_name(SpatialJointKind k) {
  switch (k) {
    case SpatialJointKind::kSpherical:
      return "spherical";
    case SpatialJointKind::kUniversal:
      return "universal";
    case SpatialJointKind::kRevolute:
      return "revolute";
    case SpatialJointKind::kCylindrical:
      return "cylindrical";
    case SpatialJointKind::kPrismatic:
      return "prismatic";
    case SpatialJointKind::kPlanar:
      return "planar";
    case SpatialJointKind::kWeld:
      return "weld";
    case SpatialJointKind::kInline:
      return "inline";
  }
  return "joint";
}

}  // namespace

std::string SpatialBodyOptions::validate() const {
  if (!(mass >= 0) || !std::isfinite(mass)) return "mass: expected a finite number >= 0";
  for (int k = 0; k < 3; ++k)
    if (!(inertia[k] >= 0) || !std::isfinite(inertia[k]))
      return "inertia: expected three finite principal moments >= 0";
  // a rigid body's principal moments obey I_k ≤ I_i + I_j (the second moments J_k ≥ 0)
  const Vec3 J = SpatialRigidInertia::second_moments(inertia);
  const double tol = 1e-12 * inertia.sum();
  for (int k = 0; k < 3; ++k)
    if (J[k] < -tol)
      return "inertia: I" + std::to_string(k + 1) +
             " exceeds the sum of the other two principal moments (no rigid body has them)";
  if (!finite(position)) return "position: expected three finite numbers";
  if (!orientation.allFinite()) return "orientation: expected finite numbers";
  const double off =
      (orientation.transpose() * orientation - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (off > 1e-9 || orientation.determinant() < 0) {
    char b[240];
    std::snprintf(
        b, sizeof b,
        "orientation: expected a rotation (orthonormal columns, determinant +1, to 1e-9); "
        "|RᵀR − I| = %.2g, det R = %.6g (give {\"axis\": [x, y, z], \"angle\": rad}, or "
        "the matrix to full precision)",
        off, orientation.determinant());
    return b;
  }
  if (velocity && !finite(*velocity)) return "velocity: expected three finite numbers";
  if (angular_velocity && !finite(*angular_velocity))
    return "angular_velocity: expected three finite numbers";
  return {};
}

std::string SpatialJointOptions::validate(SpatialJointKind kind) const {
  if (!finite(at)) return "at: expected three finite numbers";
  const bool uses_axis = kind != SpatialJointKind::kSpherical && kind != SpatialJointKind::kWeld;
  if (uses_axis && (!finite(axis) || !(axis.norm() > 0)))
    return "axis: expected a non-zero direction";
  if (kind == SpatialJointKind::kUniversal) {
    if (!axis_b) return "axis_b: a universal joint needs the cross's axis on body b";
    if (!finite(*axis_b) || !(axis_b->norm() > 0)) return "axis_b: expected a non-zero direction";
    if (std::abs(axis.normalized().dot(axis_b->normalized())) > 1e-9)
      return "axis_b: expected a direction perpendicular to axis (|cos| <= 1e-9)";
  } else if (axis_b) {
    return std::string("axis_b: only a universal joint has one (this is a ") +
           joint_kind_name(kind) + " joint)";
  }
  return {};
}

void ModelBuilder::set_spatial_gravity(const Vec3& g) {
  check_not_built();
  if (!m_->spatial_bodies().empty())
    throw std::logic_error("ModelBuilder::set_spatial_gravity after a spatial body was added");
  gravity3_ = g;
}

void ModelBuilder::spatial_body(const std::string& name, const SpatialBodyOptions& o) {
  const Entity e{"spatial body", name};
  const Mark mark = begin(e);
  check(e, o.validate());
  SpatialRigidBody b;
  b.name = name;
  b.position0 = o.position;
  b.orientation0 = o.orientation;
  b.mass_param = param(e, "mass", o.mass);
  for (int k = 0; k < 3; ++k)
    b.inertia_params[static_cast<size_t>(k)] = param(e, "I" + std::to_string(k + 1), o.inertia[k]);
  const SpatialRigidBody& sb = m_->add_spatial_body(b);
  const int d0 = sb.dof0;
  m_->add_force(std::make_unique<SpatialRigidInertia>(d0, sb.mass_param, sb.inertia_params,
                                                      gravity3_, "spatial body '" + name + "'"));
  for (const auto kind :
       {SpatialFrameConstraint::Kind::kNormal, SpatialFrameConstraint::Kind::kOrthogonal}) {
    auto c = std::make_unique<SpatialFrameConstraint>(d0, kind);
    c->set_name(name + ".frame");
    m_->add_constraint(std::move(c));
  }
  init_v_.conservativeResize(m_->nq());
  init_v_.segment<12>(d0).setZero();
  const Vec3 omega = o.angular_velocity.value_or(Vec3::Zero());
  SpatialPose::write_rates(d0, o.orientation, o.velocity.value_or(Vec3::Zero()),
                           o.orientation.transpose() * omega, init_v_);
  given_velocity(name, d0, d0 + 3, o.velocity.has_value(), o.angular_velocity.has_value(),
                 o.velocity ? "velocity" : "angular_velocity");
  commit(e, mark);
}

const SpatialRigidBody* ModelBuilder::spatial_or_ground(const Entity& e, const std::string& field,
                                                        const std::string& name) const {
  if (name == "ground") return nullptr;
  const SpatialRigidBody* b = m_->find_spatial(name);
  if (!b) {
    if (m_->find_rigid(name) || m_->find_flexible(name))
      fail(e, field, "'" + name + "' is a planar body; a spatial body is expected here");
    if (m_->find_solid(name))
      fail(e, field,
           "'" + name +
               "' is a solid body; a rigid body is expected here (tie the solid to one "
               "with a solid_connection)");
    fail(e, field, "unknown spatial body '" + name + "'");
  }
  return b;
}

const SpatialRigidBody& ModelBuilder::spatial(const std::string& name) const {
  const SpatialRigidBody* b = spatial_or_ground({}, "", name);
  if (!b) fail({}, "", "'ground' is not a spatial body");
  return *b;
}

SpatialPose ModelBuilder::pose0(const SpatialRigidBody* b) const {
  if (!b) return {Vec3::Zero(), Mat3::Identity()};
  return {b->position0, b->orientation0};
}

const SpatialJointInfo& ModelBuilder::spatial_joint(const Entity& e, const std::string& field,
                                                    const std::string& joint) const {
  auto it = spatial_joints_.find(joint);
  if (it == spatial_joints_.end()) fail(e, field, "unknown spatial joint '" + joint + "'");
  return it->second;
}

const SpatialJointInfo& ModelBuilder::spatial_joint_info(const std::string& joint) const {
  return spatial_joint({}, "", joint);
}

void ModelBuilder::spatial_joint(const std::string& name, SpatialJointKind kind,
                                 const std::string& a, const std::string& b,
                                 const SpatialJointOptions& o) {
  const Entity e{"joint", name};
  const Mark mark = begin(e);
  const SpatialRigidBody* ba = spatial_or_ground(e, "a", a);
  const SpatialRigidBody* bb = spatial_or_ground(e, "b", b);
  if (!ba && !bb) fail(e, "", "both bodies are ground");
  if (ba == bb) fail(e, "b", "a joint cannot connect a body to itself");
  check(e, o.validate(kind));
  // spherical and weld joints take no axis (SpatialJointOptions): their frame is the one about
  // z, whatever `axis` holds — a weld locks the orientation both sides share at assembly, in any
  // orthonormal frame; reading an unset axis made the weld's frame garbage
  const bool uses_axis = kind != SpatialJointKind::kSpherical && kind != SpatialJointKind::kWeld;
  SpatialJointInfo info{kind, a, b,
                        SpatialJointFrame::about(o.at, uses_axis ? o.axis : Vec3::UnitZ()), -1};
  if (kind == SpatialJointKind::kUniversal) {  // x1: the axis on a, x2: the axis on b
    info.frame.axes.col(0) = o.axis.normalized();
    info.frame.axes.col(1) = o.axis_b->normalized();
    info.frame.axes.col(2) = info.frame.axes.col(0).cross(info.frame.axes.col(1));
  }
  if (spatial_joint_rotates(kind)) info.theta_dof = m_->add_dofs(1, "joint '" + name + "' (θ)");
  const SpatialBody sa{ba ? ba->dof0 : -1}, sb{bb ? bb->dof0 : -1};
  for (auto& c : make_spatial_joint(kind, sa, pose0(ba), sb, pose0(bb), info.frame, info.theta_dof))
    add_constraint(e, std::move(c));
  for (const SpatialRigidBody* s : {ba, bb})
    if (s) m_->add_spatial_attachment(s->dof0, s->orientation0.transpose() * (o.at - s->position0));
  if (info.theta_dof >= 0) {  // the joint angle has no mass: its velocity follows the bodies'
    init_v_.conservativeResize(m_->nq());
    init_v_[info.theta_dof] = 0;
    held_v_.resize(static_cast<size_t>(m_->nq()), 0);
  }
  spatial_joints_[name] = info;
  commit(e, mark);
}

void ModelBuilder::joint_rotation_driver(const std::string& name, const std::string& joint,
                                         std::shared_ptr<const TimeLaw> law) {
  const Entity e{"joint", name};
  const Mark mark = begin(e);
  const SpatialJointInfo& j = spatial_joint(e, "joint", joint);
  if (j.theta_dof < 0)
    fail(e, "joint",
         std::string("a ") + joint_kind_name(j.kind) +
             " joint has no rotation to drive (revolute or cylindrical expected)");
  if (!law) fail(e, "law", "expected a law");
  drivers_[name] = {law, false};
  add_constraint(e, std::make_unique<AngleDriver>(-1, j.theta_dof, std::move(law)));
  commit(e, mark);
}

void ModelBuilder::joint_translation_driver(const std::string& name, const std::string& joint,
                                            std::shared_ptr<const TimeLaw> law) {
  const Entity e{"joint", name};
  const Mark mark = begin(e);
  const SpatialJointInfo& j = spatial_joint(e, "joint", joint);
  if (!spatial_joint_slides(j.kind))
    fail(e, "joint",
         std::string("a ") + joint_kind_name(j.kind) +
             " joint has no translation to drive (prismatic or cylindrical expected)");
  if (!law) fail(e, "law", "expected a law");
  const SpatialRigidBody* ba = spatial_or_ground(e, "joint", j.a);
  const SpatialRigidBody* bb = spatial_or_ground(e, "joint", j.b);
  drivers_[name] = {law, false};
  add_constraint(e, make_spatial_translation_driver(SpatialBody{ba ? ba->dof0 : -1}, pose0(ba),
                                                    SpatialBody{bb ? bb->dof0 : -1}, pose0(bb),
                                                    j.frame, std::move(law)));
  commit(e, mark);
}

void ModelBuilder::spatial_load(const std::string& name, SpatialLoad::Kind kind,
                                const std::string& body, const Vec3& at,
                                std::array<std::shared_ptr<const TimeLaw>, 3> laws,
                                SpatialLoad::Frame frame, double scale) {
  const Entity e{kind == SpatialLoad::Kind::kForce ? "force" : "torque", name};
  const Mark mark = begin(e);
  const SpatialRigidBody* b = spatial_or_ground(e, "body", body);
  if (!b) fail(e, "body", "a load must act on a body");
  if (!finite(at)) fail(e, "at", "expected three finite numbers");
  if (!std::isfinite(scale)) fail(e, "scale", "expected a finite number");
  const Vec3 d = b->orientation0.transpose() * (at - b->position0);
  const int sp = param(e, "scale", scale);
  m_->add_force(std::make_unique<SpatialLoad>(b->dof0, kind, frame, d, std::move(laws), sp,
                                              e.kind + " '" + name + "'"));
  if (kind == SpatialLoad::Kind::kForce) m_->add_spatial_attachment(b->dof0, d);
  commit(e, mark);
}

void ModelBuilder::spatial_spring_damper(const std::string& name, const std::string& a,
                                         const Vec3& a_at, const std::string& b, const Vec3& b_at,
                                         const SpringOptions& o) {
  const Entity e{"spring", name};
  const Mark mark = begin(e);
  const SpatialRigidBody* ba = spatial_or_ground(e, "a", a);
  const SpatialRigidBody* bb = spatial_or_ground(e, "b", b);
  if (!ba && !bb) fail(e, "", "both ends are ground");
  if (!finite(a_at)) fail(e, "a_at", "expected three finite numbers");
  if (!finite(b_at)) fail(e, "b_at", "expected three finite numbers");
  check(e, o.validate());
  const double l_init = (b_at - a_at).norm();
  if (!(l_init > 0))
    fail(e, "", "the spring's end points coincide initially (direction undefined)");
  const auto local = [](const SpatialRigidBody* s, const Vec3& x) -> Vec3 {
    return s ? Vec3(s->orientation0.transpose() * (x - s->position0)) : x;
  };
  const int kp = param(e, "stiffness", o.stiffness);
  const int cp = param(e, "damping", o.damping);
  const int lp = param(e, "free_length", o.free_length.value_or(l_init));
  m_->add_force(std::make_unique<SpatialSpringDamper>(
      SpatialBody{ba ? ba->dof0 : -1}, local(ba, a_at), SpatialBody{bb ? bb->dof0 : -1},
      local(bb, b_at), kp, cp, lp, "spring '" + name + "'"));
  if (ba) m_->add_spatial_attachment(ba->dof0, local(ba, a_at));
  if (bb) m_->add_spatial_attachment(bb->dof0, local(bb, b_at));
  commit(e, mark);
}

void ModelBuilder::joint_spring_damper(const std::string& name, const std::string& joint,
                                       const RotationalSpringOptions& o) {
  const Entity e{"rotational spring", name};
  const Mark mark = begin(e);
  const SpatialJointInfo& j = spatial_joint(e, "joint", joint);
  if (j.theta_dof < 0)
    fail(e, "joint",
         std::string("a ") + joint_kind_name(j.kind) +
             " joint has no rotation (revolute or cylindrical expected)");
  check(e, o.validate());
  const int kp = param(e, "stiffness", o.stiffness);
  const int cp = param(e, "damping", o.damping);
  const int tp = param(e, "free_angle", o.free_angle.value_or(0.0));
  // the moment acts on the joint angle; the angle's equation hands it to the two bodies
  m_->add_force(std::make_unique<RotationalSpringDamper>(j.theta_dof, -1, kp, cp, tp,
                                                         "rotational spring '" + name + "'"));
  commit(e, mark);
}

}  // namespace lsmbs

namespace lsmbs {

std::string SolidBodyOptions::validate() const {
  if (!(E > 0) || !std::isfinite(E)) return "E: expected a positive number";
  if (!(nu > -1 && nu < 0.5)) return "nu: expected a number in (-1, 0.5)";
  if (!(rho >= 0) || !std::isfinite(rho)) return "rho: expected a number >= 0";
  return {};
}

void ModelBuilder::solid_body(const std::string& name, SolidMesh mesh, const SolidBodyOptions& o) {
  const Entity e{"solid body", name};
  const Mark mark = begin(e);
  check(e, o.validate());
  if (mesh.num_elements() == 0) fail(e, "mesh", "expected at least one cell");
  for (const auto& [set, nodes] : mesh.node_sets) {
    if (nodes.empty()) fail(e, "node_sets/" + set, "node set '" + set + "' is empty");
    for (int n : nodes)
      if (n < 0 || n >= mesh.num_nodes())
        fail(e, "node_sets/" + set,
             "node set '" + set + "' holds node " + std::to_string(n) + " (the mesh has " +
                 std::to_string(mesh.num_nodes()) + " nodes)");
  }
  for (size_t c = 0; c < mesh.cells.size(); ++c)
    for (int n : mesh.cells[c])
      if (n < 0 || n >= mesh.num_nodes())
        fail(e, "mesh", "cell " + std::to_string(c) + " names node " + std::to_string(n));
  SolidBody b;
  b.name = name;
  b.mesh = std::move(mesh);
  b.E_param = param(e, "E", o.E);
  b.nu_param = param(e, "nu", o.nu);
  b.rho_param = param(e, "rho", o.rho);
  b.gravity = gravity3_;
  b.formulation = o.formulation;
  const SolidBody* added = nullptr;
  try {  // the element geometry is checked here (inverted or degenerate cells)
    added = &m_->add_solid_body(std::move(b));
  } catch (const Error& err) {  // the model holds the body's unknowns already: the builder is spent
    broken_ = true;
    fail(e, "mesh", err.what());
  }
  init_v_.conservativeResize(m_->nq());
  init_v_.segment(added->dof0, 3 * added->mesh.num_nodes()).setZero();
  commit(e, mark);
}

const SolidBody& ModelBuilder::solid(const std::string& name) const {
  const SolidBody* b = m_->find_solid(name);
  if (!b && m_->find_spatial(name))
    fail({}, "", "'" + name + "' is a rigid body; a solid body is expected here");
  if (!b) fail({}, "", "unknown solid body '" + name + "'");
  return *b;
}

void ModelBuilder::solid_connection(const std::string& name, const std::string& solid_body,
                                    const std::string& node_set, const std::string& body) {
  const Entity e{"joint", name};
  const Mark mark = begin(e);
  const SolidBody* sb = m_->find_solid(solid_body);
  if (!sb && m_->find_spatial(solid_body))
    fail(e, "solid", "'" + solid_body + "' is a rigid body; a solid body is expected here");
  if (!sb) fail(e, "solid", "unknown solid body '" + solid_body + "'");
  const auto set = sb->mesh.node_sets.find(node_set);
  if (set == sb->mesh.node_sets.end())
    fail(e, "node_set",
         "solid body '" + solid_body + "' has no node set '" + node_set + "' (it has " +
             sb->mesh.node_set_names() + ")");
  const SpatialRigidBody* rb = spatial_or_ground(e, "body", body);
  // nodes tied before (two faces sharing an edge): once to the same body, never to another
  std::map<int, const ConstraintElement*> tied;
  for (const auto& c : m_->constraints())
    if (dynamic_cast<const SolidNodeLink*>(c.get())) tied[c->dofs()[0]] = c.get();
  const int target = rb ? rb->dof0 : -1;
  for (int n : set->second) {
    if (const auto it = tied.find(sb->node_dof(n)); it != tied.end()) {
      const auto d = it->second->dofs();
      const int other = d.size() > 3 ? d[3] : -1;
      if (other == target) continue;  // already tied there by another face
      fail(e, "node_set",
           "node " + std::to_string(n) + " of '" + solid_body + "' is tied by '" +
               it->second->name() + "' to another body already (a node follows one body)");
    }
    const Vec3& X = sb->mesh.nodes[static_cast<size_t>(n)];
    if (rb) {
      const Vec3 d = rb->orientation0.transpose() * (X - rb->position0);
      add_constraint(e, std::make_unique<SolidNodeLink>(sb->node_dof(n), rb->dof0, d));
      m_->add_spatial_attachment(rb->dof0, d);
    } else {
      add_constraint(e, std::make_unique<SolidNodeLink>(sb->node_dof(n), -1, X));
    }
  }
  commit(e, mark);
}

}  // namespace lsmbs
