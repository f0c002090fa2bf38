#pragma once
// ModelBuilder — builds a Model from named entities: rigid and flexible bodies, joints, drivers
// and forces, each referred to by its name, and points referred to by the body they sit on. The
// elements of constraints.hpp and forces.hpp only know DOF indices and parameter indices; the
// builder owns the modelling conventions that connect them to names (docs/library.md):
//
//  * a rigid body is three unknowns (x, y, θ of its reference point) and a RigidInertia element
//    (mass m at the body-frame offset c, rotary inertia J_c about the centre of mass) with the
//    parameters "<body>.mass" and "<body>.inertia";
//  * a flexible body is the nodal positions of its placed mesh and one PlaneForce per cell, with
//    the parameters "<body>.E", "<body>.nu", "<body>.rho" and "<body>.thickness" (eq. 3);
//  * a revolute joint is a PointCoincidence, by default with the ground point at the initial
//    position of point a; a rigid connection is one PointCoincidence per node of a node set
//    (each node keeps its initial offset in the rigid body's frame); a clamp fixes each node of a
//    node set at its initial position; a prismatic joint slides through the initial position of
//    its point and locks the body's initial angle;
//  * forces create parameters "<force>.<property>" (a spring's free length defaults to the
//    initial distance of its end points, a rotational spring's free angle to the initial
//    relative angle); a point mass on a node is a NodeMass, on a rigid body a RigidInertia
//    without rotary inertia;
//  * the initial state: positions from the placements, the velocities the bodies give (a
//    flexible body's rigid velocity field v + ω × (x − origin)), and which velocities were given
//    (the initial projection keeps them, integrators/initial_state.hpp);
//  * build() refuses a rigid body that no mass, inertia or constraint determines.
//
// DOFs, parameters, force elements and constraint elements are numbered in the order of the
// calls. Bodies, joints and forces share one namespace of names; "ground" is not a body name.
//
// Errors are ModelError (core/error.hpp): the entity ("joint 'pivot'") and the argument at fault,
// named as in the case format ("a/body", "node_set"), e.g.
//   joint 'pivot', a/body: unknown body 'crnk'
// The JSON loader maps them to the JSON path of the entry (io/case_loader.cpp). A call that throws
// changes nothing (the builder can be used further), except a flexible body whose mesh has inverted
// or degenerate elements: the builder then refuses further calls.
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/mesh.hpp"
#include "lsmbs/mbs/model.hpp"
#include "lsmbs/mbs/spatial_force.hpp"
#include "lsmbs/mbs/spatial_joint.hpp"

namespace lsmbs {

/// A material point named by the body it sits on; the builder resolves it to a PointRef.
struct Point {
  enum class Kind {
    kGround,     ///< fixed at x
    kBodyFrame,  ///< rigid body, offset x in its body frame
    kGlobal,     ///< rigid body, the material point at x at t = 0
    kNode,       ///< flexible body, node `index`
    kNearest     ///< flexible body, the node nearest to x (mesh frame)
  };
  Kind kind = Kind::kGround;
  std::string body;
  Vec2 x = Vec2::Zero();
  int index = -1;

  static Point ground(const Vec2& x) { return {Kind::kGround, "", x, -1}; }
  static Point at(std::string body, const Vec2& offset = Vec2::Zero()) {
    return {Kind::kBodyFrame, std::move(body), offset, -1};
  }
  static Point at_global(std::string body, const Vec2& x) {
    return {Kind::kGlobal, std::move(body), x, -1};
  }
  static Point node(std::string body, int index) {
    return {Kind::kNode, std::move(body), Vec2::Zero(), index};
  }
  static Point nearest(std::string body, const Vec2& x_mesh) {
    return {Kind::kNearest, std::move(body), x_mesh, -1};
  }
};

struct RigidBodyOptions {
  double mass = 0;               ///< m ≥ 0 (parameter "<body>.mass")
  double inertia = 0;            ///< J_c ≥ 0 about the centre of mass ("<body>.inertia")
  Vec2 position = Vec2::Zero();  ///< reference point at t = 0
  double angle = 0;              ///< θ at t = 0
  Vec2 com = Vec2::Zero();       ///< centre of mass in the body frame
  std::optional<Vec2> velocity;  ///< of the reference point at t = 0 (given: kept)
  std::optional<double> angular_velocity;  ///< θ̇ at t = 0 (given: kept)
  /// Empty string when valid, otherwise "field: what is expected" (the builder reports it as a
  /// ModelError naming the entity and the field).
  std::string validate() const;
};

struct FlexibleBodyOptions {
  double E = 0;          ///< Young's modulus E0 > 0 of the full material (μ = 1)
  double nu = 0;         ///< Poisson's ratio in [0, 0.5)
  double rho = 0;        ///< density ρ0 > 0
  double thickness = 0;  ///< plane-stress thickness > 0
  /// Every strain term at the full Gauss rule (a Q4 then locks in bending); default: the
  /// element's own remedy (fem/plane_element.hpp, ElementOptions)
  bool full_integration = false;
  Vec2 origin = Vec2::Zero();  ///< placement of the mesh frame at t = 0: x = origin + R(angle) X
  double angle = 0;
  /// Rigid velocity field at t = 0, v + ω × (x − origin); either given: the whole field is kept.
  std::optional<Vec2> velocity;
  std::optional<double> angular_velocity;
  /// Empty string when valid, otherwise "field: what is expected" (the builder reports it as a
  /// ModelError naming the entity and the field).
  std::string validate() const;
};

struct PrismaticOptions {
  std::optional<Vec2> through;  ///< a point of the line (default: the initial position of a)
  bool lock_rotation = true;    ///< also θ_a = θ_a(0) (rigid-body points only)
  /// Empty string when valid, otherwise "field: what is expected" (the builder reports it as a
  /// ModelError naming the entity and the field).
  std::string validate() const;
};

struct SpringOptions {
  double stiffness = 0, damping = 0;
  std::optional<double> free_length;  ///< default: the initial distance of the end points
  /// Empty string when valid, otherwise "field: what is expected" (the builder reports it as a
  /// ModelError naming the entity and the field).
  std::string validate() const;
};

struct RotationalSpringOptions {
  double stiffness = 0, damping = 0;
  std::optional<double> free_angle;  ///< default: the initial relative angle θa − θb
  /// Empty string when valid, otherwise "field: what is expected" (the builder reports it as a
  /// ModelError naming the entity and the field).
  std::string validate() const;
};

/// A spatial rigid body in natural coordinates (mbs/spatial.hpp).
struct SpatialBodyOptions {
  double mass = 0;               ///< m ≥ 0 (parameter "<body>.mass")
  Vec3 inertia = Vec3::Zero();   ///< principal moments about the centre of mass ("<body>.I1" …)
  Vec3 position = Vec3::Zero();  ///< centre of mass at t = 0
  Mat3 orientation = Mat3::Identity();   ///< principal axes at t = 0 (columns; a rotation)
  std::optional<Vec3> velocity;          ///< of the centre of mass at t = 0 (given: kept)
  std::optional<Vec3> angular_velocity;  ///< ω at t = 0, global components (given: kept)
  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

/// A 3D solid flexible body (mbs/solid_body.hpp): St Venant–Kirchhoff, eq. (3)'s μ_e E0, μ_e ρ0.
struct SolidBodyOptions {
  double E = 0, nu = 0.3, rho = 0;  ///< parameters "<body>.E", "<body>.nu", "<body>.rho"
  /// Hexahedra: enhanced assumed strains (default; no locking) or the plain 2 × 2 × 2 brick.
  HexElement::Formulation formulation = HexElement::Formulation::kEnhanced;
  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

/// Where a spatial joint sits at assembly (t = 0) and its axes, in global components.
struct SpatialJointOptions {
  Vec3 at = Vec3::Zero();  ///< the joint's point
  /// revolute, cylindrical, prismatic: the axis; planar: the normal; universal: the cross's axis
  /// on body a; spherical, weld: unused
  Vec3 axis = Vec3::UnitZ();
  std::optional<Vec3> axis_b;  ///< universal: the cross's axis on body b (⟂ axis)
  /// Empty string when valid for that kind, otherwise "field: what is expected".
  std::string validate(SpatialJointKind kind) const;
};

/// A spatial joint as built: its kind, bodies, frame and joint angle unknown (−1: none).
struct SpatialJointInfo {
  SpatialJointKind kind = SpatialJointKind::kSpherical;
  std::string a, b;
  SpatialJointFrame frame;
  int theta_dof = -1;
};

/// The argument of a pressure table: the time (angle_of empty) plus offset, or the angle of a
/// rigid body plus offset.
struct PressureArgument {
  std::string angle_of;
  double offset = 0;
};

/// A driver by name: its law and whether it prescribes an angle relative to another body.
struct DriverInfo {
  std::shared_ptr<const TimeLaw> law;
  bool relative = false;
};

/// Velocities one body gives at t = 0: its unknowns [first, end) and the option that gave them
/// ("velocity", or "angular_velocity" when only that one was given).
struct GivenVelocity {
  std::string body, field;
  int first = 0, end = 0;
};

/// What the start checks of a study (Study::prepare) need from the building of its model: the
/// state as the bodies are placed, which velocities were given, and which entity (a body or
/// force, by name) made each force element and each parameter, for messages that name it.
struct ModelStart {
  State placed;  ///< t = 0, positions and given velocities as placed (before the projection)
  std::vector<char> held_velocities;  ///< per unknown: its initial velocity was given
  std::vector<GivenVelocity>
      given_velocities;                   ///< per body (or initial-state entry) that gives some
  std::vector<std::string> force_owners;  ///< per force element: its body or force
  std::map<std::string, std::vector<int>> entity_parameters;  ///< the parameters of each entity
};

class ModelBuilder {
 public:
  enum class BodyKind { kNone, kRigid, kFlexible, kSpatial };

  ModelBuilder();
  ModelBuilder(const ModelBuilder&) = delete;
  ModelBuilder& operator=(const ModelBuilder&) = delete;

  void set_gravity(const Vec2& g);

  // ------------------------------------------------------------ bodies
  void rigid_body(const std::string& name, const RigidBodyOptions& o);
  /// The mesh is in the body's own (design) frame; its node sets (Mesh2D::node_sets: a rectangle's
  /// sides, Gmsh physical groups, or sets added with the Mesh2D selectors) are the sets joints
  /// refer to, each non-empty.
  void flexible_body(const std::string& name, Mesh2D mesh, const FlexibleBodyOptions& o);

  // ------------------------------------------------------------ spatial (mbs/spatial*.hpp)
  /// Gravity of the spatial bodies (set before adding any).
  void set_spatial_gravity(const Vec3& g);
  /// Twelve unknowns (centre of mass, principal axes), a SpatialRigidInertia and its six frame
  /// constraints (named "<body>.frame"); parameters "<body>.mass", "<body>.I1", "I2", "I3".
  void spatial_body(const std::string& name, const SpatialBodyOptions& o);
  /// A joint of that kind between spatial bodies a and b ("ground" for one of them), its frame
  /// equal on both at assembly. A revolute or cylindrical joint also gets its rotation angle θ
  /// (one more unknown, 0 at assembly).
  void spatial_joint(const std::string& name, SpatialJointKind kind, const std::string& a,
                     const std::string& b, const SpatialJointOptions& o);
  /// θ − s(t) = 0 on the rotation of a revolute or cylindrical joint.
  void joint_rotation_driver(const std::string& name, const std::string& joint,
                             std::shared_ptr<const TimeLaw> law);
  /// a₃·(x_b − x_a) − s(t) = 0 along a prismatic or cylindrical joint's axis (0 at assembly).
  void joint_translation_driver(const std::string& name, const std::string& joint,
                                std::shared_ptr<const TimeLaw> law);
  /// A force at the body point that is at `at` (global) at t = 0, or (torque) a moment on the
  /// body: scale · (L₁, L₂, L₃)(t) in the ground frame or the body's principal frame; null laws
  /// are zero. Parameter "<force>.scale".
  void spatial_load(const std::string& name, SpatialLoad::Kind kind, const std::string& body,
                    const Vec3& at, std::array<std::shared_ptr<const TimeLaw>, 3> laws,
                    SpatialLoad::Frame frame, double scale = 1);
  /// Between the body points at a_at and b_at (global, t = 0); b may be "ground".
  void spatial_spring_damper(const std::string& name, const std::string& a, const Vec3& a_at,
                             const std::string& b, const Vec3& b_at, const SpringOptions& o);
  /// M = k (θ − θ0) + c θ̇ on a revolute or cylindrical joint's angle (θ0 default 0).
  void joint_spring_damper(const std::string& name, const std::string& joint,
                           const RotationalSpringOptions& o);
  /// A solid body meshed by `mesh` (node positions at t = 0, ground frame), at rest; its weight
  /// under the spatial gravity.
  void solid_body(const std::string& name, SolidMesh mesh, const SolidBodyOptions& o);
  /// Every node of the node set stays where it is at t = 0 (body "ground") or keeps its offset
  /// in a spatial body's principal frame.
  void solid_connection(const std::string& name, const std::string& solid,
                        const std::string& node_set, const std::string& body);
  const SolidBody& solid(const std::string& name) const;
  const SpatialRigidBody& spatial(const std::string& name) const;
  /// The spatial joint of that name (ModelError if there is none).
  const SpatialJointInfo& spatial_joint_info(const std::string& joint) const;

  // ------------------------------------------------------------ joints and drivers
  /// p_a = p_b; b defaults to the ground point at the initial position of a.
  void revolute(const std::string& name, const Point& a,
                const std::optional<Point>& b = std::nullopt);
  /// Point a (on a body) slides on a line of the given direction.
  void prismatic(const std::string& name, const Point& a, const Vec2& direction,
                 const PrismaticOptions& o = {});
  /// Every node of the node set keeps its initial offset in the rigid body's frame.
  void rigid_connection(const std::string& name, const std::string& rigid,
                        const std::string& flexible, const std::string& node_set);
  /// Every node of the node set stays at its initial position.
  void clamp(const std::string& name, const std::string& flexible, const std::string& node_set);
  /// θ_body − θ_relative_to − s(t) = 0 (relative_to "ground": θ_ground = 0).
  void rotation_driver(const std::string& name, const std::string& body,
                       std::shared_ptr<const TimeLaw> law,
                       const std::string& relative_to = "ground");
  /// u·(p − x0) − s(t) = 0, x0 = through (default: the initial position of the point).
  void translation_driver(const std::string& name, const Point& point, const Vec2& direction,
                          std::shared_ptr<const TimeLaw> law,
                          const std::optional<Vec2>& through = std::nullopt);

  // ------------------------------------------------------------ forces
  void point_mass(const std::string& name, const Point& point, double mass);
  /// F(t) = scale · (fx(t), fy(t)) in the inertial frame; a null law is zero.
  void point_force(const std::string& name, const Point& point, std::shared_ptr<const TimeLaw> fx,
                   std::shared_ptr<const TimeLaw> fy, double scale = 1);
  void point_force(const std::string& name, const Point& point, const Vec2& force,
                   double scale = 1);
  void spring_damper(const std::string& name, const Point& a, const Point& b,
                     const SpringOptions& o);
  /// Moment scale · T(t) on a rigid body's angle.
  void torque(const std::string& name, const std::string& body, std::shared_ptr<const TimeLaw> law,
              double scale = 1);
  void torque(const std::string& name, const std::string& body, double torque, double scale = 1);
  /// Between the angles of rigid bodies a and b (b may be "ground").
  void rotational_spring_damper(const std::string& name, const std::string& a, const std::string& b,
                                const RotationalSpringOptions& o);
  /// Pressure P(s) × area along a fixed direction at a point (s: the time or a body's angle).
  void pressure(const std::string& name, const Point& point, const Vec2& direction, double area,
                Table1D table, const PressureArgument& argument = {});

  /// The admissible range of a model parameter by its property ("<entity>.<property>": E > 0,
  /// 0 ≤ nu < 0.5, rho, thickness and area > 0, mass, inertia, stiffness, damping and
  /// free_length ≥ 0, every value finite): "" when `value` is admissible, else what is expected,
  /// in the case loader's words for the same value in a case file. The loader checks parameters
  /// bound to design variables with it over the variables' bounds; Python checks a parameter it
  /// sets.
  static std::string check_parameter_value(const std::string& name, double value);

  // ------------------------------------------------------------ queries by name
  /// Throws the ModelError (field "name") that adding an entity of that name would meet: the name
  /// is taken, or, for a body, it is "ground". Every add checks it; a reader may check it early.
  void check_name(const std::string& name, bool body) const;
  BodyKind body_kind(const std::string& name) const;
  /// The point's DOFs and local coordinates (errors name the field "body" or "node").
  PointRef resolve(const Point& p) const;
  /// Position of a point at t = 0.
  Vec2 initial_position(const Point& p) const;
  Vec2 initial_position(const PointRef& p) const;
  /// The angle unknown θ of a rigid body.
  int angle_dof(const std::string& rigid_body) const;
  const RigidBody& rigid(const std::string& name) const;
  const FlexibleBody& flexible(const std::string& name) const;
  /// Index of a model parameter ("<entity>.<property>"), −1 if there is none.
  int parameter(const std::string& name) const { return m_->parameter_index(name); }
  /// The parameters an entity created, in order (none for joints).
  std::vector<int> parameters_of(const std::string& entity) const;
  /// The driver of that name, or null.
  const DriverInfo* driver(const std::string& name) const;
  const std::map<std::string, DriverInfo>& drivers() const { return drivers_; }
  /// Number of constraint equations of a joint (rows are numbered by build()).
  int joint_equations(const std::string& joint) const;
  /// The body or force whose entry created force element f (Model::forces()).
  const std::string& force_owner(size_t f) const;
  /// The model: under construction, or after build() the one handed over (which the caller must
  /// keep alive while it queries the builder).
  const Model& model() const { return *m_; }

  // ------------------------------------------------------------ build
  /// Checks that every rigid body is determined (a mass, an inertia or a constraint), finalizes
  /// the model and hands it over. The queries above stay valid; nothing can be added afterwards.
  std::unique_ptr<Model> build();
  bool built() const { return built_; }
  /// After build(): t = 0, positions of the placements, the given velocities (others zero),
  /// q̈ = 0, λ = 0 (a starting point: the integrators make it consistent).
  const State& initial_state() const;
  /// After build(): per unknown, whether its initial velocity was given.
  const std::vector<char>& held_velocities() const { return held_v_; }
  const std::vector<GivenVelocity>& given_velocities() const { return given_v_; }
  /// After build(): what the start checks need (Study::prepare).
  ModelStart start() const;
  /// After build(): the constraint rows (indices into Φ) of a joint, and of every joint.
  const std::vector<int>& joint_rows(const std::string& joint) const;
  const std::map<std::string, std::vector<int>>& joint_rows() const { return joint_rows_; }

 private:
  struct Entity {  // the entity being added, for messages: "joint 'pivot'"
    std::string kind, name;
  };
  struct Mark {  // the model's force and constraint elements before an entity is added
    size_t force = 0, constraint = 0;
  };
  [[noreturn]] static void fail(const Entity& e, const std::string& field, const std::string& what);
  static void check(const Entity& e, const std::string& validation);
  // Every call checks everything (begin: the name) before it changes the model, and registers the
  // entity at the end (commit): a call that throws leaves the builder as it was.
  Mark begin(const Entity& e) const;
  void check_name(const Entity& e, bool body) const;
  void commit(const Entity& e, const Mark& mark);
  void add_constraint(const Entity& e, std::unique_ptr<ConstraintElement> c);
  PointRef resolve(const Entity& e, const std::string& field, const Point& p) const;
  const RigidBody& rigid(const Entity& e, const std::string& field, const std::string& name) const;
  const FlexibleBody& flexible(const Entity& e, const std::string& field,
                               const std::string& name) const;
  const std::vector<int>& node_set(const Entity& e, const std::string& field, const FlexibleBody& b,
                                   const std::string& set) const;
  int param(const Entity& e, const std::string& property, double value);
  void given_velocity(const std::string& body, int first, int rotation_dof, bool translation,
                      bool rotation, const std::string& field);
  void check_not_built() const;
  void check_determined() const;
  const SpatialRigidBody* spatial_or_ground(const Entity& e, const std::string& field,
                                            const std::string& name) const;
  const SpatialJointInfo& spatial_joint(const Entity& e, const std::string& field,
                                        const std::string& joint) const;
  SpatialPose pose0(const SpatialRigidBody* b) const;

  std::unique_ptr<Model> model_;  // owned until build()
  Model* m_ = nullptr;            // the model, before and after build()
  bool built_ = false;
  bool broken_ = false;  // a flexible body's mesh was refused after its unknowns were allocated
  std::set<std::string> names_;
  std::vector<std::pair<size_t, std::string>> force_owners_;         // first force element, entity
  std::map<std::string, std::pair<size_t, size_t>> joint_elements_;  // constraint elements [b, e)
  std::map<std::string, std::vector<int>> joint_rows_;
  std::map<std::string, DriverInfo> drivers_;
  std::map<std::string, SpatialJointInfo> spatial_joints_;
  Vec3 gravity3_ = Vec3::Zero();
  std::map<std::string, std::vector<int>> entity_params_;
  Vec init_v_;
  std::vector<char> held_v_;
  std::vector<GivenVelocity> given_v_;
  State initial_;
};

}  // namespace lsmbs
