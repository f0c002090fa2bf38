// Joints, drivers and loads of spatial rigid bodies in natural coordinates (mbs/spatial_joint.hpp,
// mbs/spatial_force.hpp) against independent references:
//  - every joint's equations vanish at assembly, and their Jacobian, Hessian contraction and
//    time derivatives agree with central differences at states off the constraint manifold;
//  - kinematics: each joint lets through exactly the relative rigid motions (twists) its kind
//    names in closed form (a revolute: the rotation about its axis; a planar joint: two
//    translations in its plane and the rotation about its normal; …) and stops the rest, i.e. its
//    Jacobian annihilates the allowed twists and has full rank on their complement;
//  - the joint angle follows a relative rotation through several turns;
//  - loads: tangents and parameter derivatives against central differences, and the power of
//    the generalized forces on a rigid motion equal to F·v and T·ω computed directly.
#include "lsmbs/mbs/spatial_joint.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <numbers>
#include <random>

#include "lsmbs/mbs/forces.hpp"
#include "lsmbs/mbs/spatial_force.hpp"
#include "support/element_checks.hpp"

using namespace lsmbs;
using K = SpatialJointKind;

namespace {

Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> N;
  const Eigen::Quaterniond q(N(rng), N(rng), N(rng), N(rng));
  return q.normalized().toRotationMatrix();
}

Vec3 random_vec(std::mt19937& rng, double scale = 1) { return checks::random_local(3, rng, scale); }

// A rigid motion's natural-coordinate rates: ṙ = v + ω × (r − p), ė_k = ω × e_k.
void twist_rates(const SpatialPose& P, const Vec3& omega, const Vec3& v_at_p, const Vec3& p,
                 Vec& qdot, int dof0) {
  qdot.segment<3>(dof0) = v_at_p + omega.cross(P.r - p);
  for (int k = 0; k < 3; ++k) qdot.segment<3>(dof0 + 3 + 3 * k) = omega.cross(P.R.col(k));
}

LocalVec gather(const ConstraintElement& c, const Vec& x) {
  const auto d = c.dofs();
  LocalVec z(static_cast<Eigen::Index>(d.size()));
  for (size_t i = 0; i < d.size(); ++i) z[static_cast<Eigen::Index>(i)] = x[d[i]];
  return z;
}

const std::vector<K>& all_kinds() {
  static const std::vector<K> k = {K::kSpherical, K::kUniversal, K::kRevolute, K::kCylindrical,
                                   K::kPrismatic, K::kPlanar,    K::kWeld,     K::kInline};
  return k;
}

// The relative twists of B with respect to A that the joint allows, as (ω, v at the joint
// point) pairs in the joint frame's axes x1, x2, x3 (columns of f.axes).
std::vector<std::pair<Vec3, Vec3>> allowed_twists(K kind, const Mat3& x) {
  const Vec3 z = Vec3::Zero();
  switch (kind) {
    case K::kSpherical:
      return {{x.col(0), z}, {x.col(1), z}, {x.col(2), z}};
    case K::kUniversal:
      return {{x.col(0), z}, {x.col(1), z}};
    case K::kRevolute:
      return {{x.col(2), z}};
    case K::kCylindrical:
      return {{x.col(2), z}, {z, x.col(2)}};
    case K::kPrismatic:
      return {{z, x.col(2)}};
    case K::kPlanar:
      return {{x.col(2), z}, {z, x.col(0)}, {z, x.col(1)}};
    case K::kWeld:
      return {};
    case K::kInline:
      return {{x.col(0), z}, {x.col(1), z}, {x.col(2), z}, {z, x.col(2)}};
  }
  return {};
}

// Two bodies (A at DOF 0, B at 12; θ at 24) at random poses, a joint frame at a random point.
struct Assembly {
  SpatialPose A, B;
  SpatialJointFrame f;
  Vec q = Vec::Zero(25);
  explicit Assembly(std::mt19937& rng) {
    A = {random_vec(rng), random_rotation(rng)};
    B = {random_vec(rng), random_rotation(rng)};
    f = SpatialJointFrame::about(random_vec(rng, 0.5), random_vec(rng));
    A.write(0, q);
    B.write(12, q);
  }
};

}  // namespace

TEST(SpatialJoints, VanishAtAssemblyAndTheirDerivativesAgreeWithCentralDifferences) {
  std::mt19937 rng(11);
  for (const K kind : all_kinds()) {
    for (int ground = 0; ground < 3; ++ground) {  // both bodies; A is ground; B is ground
      SCOPED_TRACE(static_cast<int>(kind) * 10 + ground);
      const Assembly as(rng);
      const SpatialBody a{ground == 1 ? -1 : 0}, b{ground == 2 ? -1 : 12};
      const auto elems = make_spatial_joint(kind, a, as.A, b, as.B, as.f, 24);
      int equations = 0;
      for (const auto& c : elems) {
        equations += c->size();
        LocalEqVec phi;
        c->evaluate(0, gather(*c, as.q), ModelParams{}, phi, nullptr);
        EXPECT_LT(phi.cwiseAbs().maxCoeff(), 1e-12);
        // off the manifold, where every term of the derivatives is alive
        const LocalVec z =
            gather(*c, as.q) + checks::random_local(static_cast<int>(c->dofs().size()), rng, 0.3);
        const auto e = checks::check_constraint(*c, 0, z, checks::random_local(c->size(), rng));
        EXPECT_LT(e.jacobian, 1e-8);
        EXPECT_LT(e.hessian, 1e-8);
        EXPECT_LT(e.time, 1e-8);
      }
      const int rotates = spatial_joint_rotates(kind) ? 1 : 0;
      EXPECT_EQ(equations,
                6 - static_cast<int>(allowed_twists(kind, Mat3::Identity()).size()) + rotates);
    }
  }
}

TEST(SpatialJoints, AllowExactlyTheRelativeMotionsOfTheirKind) {
  std::mt19937 rng(5);
  for (const K kind : all_kinds()) {
    SCOPED_TRACE(static_cast<int>(kind));
    const Assembly as(rng);
    const auto elems =
        make_spatial_joint(kind, SpatialBody{0}, as.A, SpatialBody{12}, as.B, as.f, -1);
    // the joint's Jacobian on B's coordinates (A held still), as a map of B's twists
    const auto jac_times = [&](const Vec3& w, const Vec3& v) {
      Vec qdot = Vec::Zero(25);
      twist_rates(as.B, w, v, as.f.point, qdot, 12);
      Vec out(0);
      for (const auto& c : elems) {
        LocalEqVec phi;
        LocalJac J;
        c->evaluate(0, gather(*c, as.q), ModelParams{}, phi, &J);
        const Vec part = J * gather(*c, qdot);
        out.conservativeResize(out.size() + part.size());
        out.tail(part.size()) = part;
      }
      return out;
    };
    const auto allowed = allowed_twists(kind, as.f.axes);
    for (const auto& [w, v] : allowed) EXPECT_LT(jac_times(w, v).norm(), 1e-12);
    // rank on all six twists = number of equations = 6 − allowed motions
    Mat T(static_cast<Eigen::Index>(jac_times(Vec3::UnitX(), Vec3::Zero()).size()), 6);
    for (int i = 0; i < 6; ++i)
      T.col(i) = i < 3 ? jac_times(Vec3::Unit(i), Vec3::Zero())
                       : jac_times(Vec3::Zero(), Vec3::Unit(i - 3));
    const Eigen::JacobiSVD<Mat> svd(T);
    const int rank = static_cast<int>((svd.singularValues().array() > 1e-8).count());
    EXPECT_EQ(rank, 6 - static_cast<int>(allowed.size()));
    EXPECT_EQ(T.rows(), 6 - static_cast<Eigen::Index>(allowed.size()));
  }
}

TEST(SpatialJoints, TheJointAngleFollowsTheRelativeRotationThroughSeveralTurns) {
  std::mt19937 rng(7);
  for (const K kind : {K::kRevolute, K::kCylindrical}) {
    for (const double theta : {0.3, 2.5, -4.0, 7.0, 20.0}) {
      Assembly as(rng);
      const auto elems =
          make_spatial_joint(kind, SpatialBody{0}, as.A, SpatialBody{12}, as.B, as.f, 24);
      // B turned by θ about the axis through the joint point: the configuration is admissible
      // with the joint coordinate θ and not with θ ± 0.1
      const Mat3 Rz = Eigen::AngleAxisd(theta, as.f.axes.col(2)).toRotationMatrix();
      SpatialPose B = {as.f.point + Rz * (as.B.r - as.f.point), Rz * as.B.R};
      B.write(12, as.q);
      const ConstraintElement& angle = *elems.back();
      for (const double dt : {0.0, 0.1, -0.1}) {
        as.q[24] = theta + dt;
        LocalEqVec phi;
        LocalJac J;
        angle.evaluate(0, gather(angle, as.q), ModelParams{}, phi, &J);
        if (dt == 0) {
          EXPECT_LT(std::abs(phi[0]), 1e-12);
          EXPECT_NEAR(J(0, J.cols() - 1), -1.0, 1e-12);  // ∂Φ/∂θ on the manifold
        } else {
          EXPECT_NEAR(std::abs(phi[0]), std::sin(0.1), 1e-12);
        }
      }
      for (size_t i = 0; i + 1 < elems.size(); ++i) {
        LocalEqVec phi;
        elems[i]->evaluate(0, gather(*elems[i], as.q), ModelParams{}, phi, nullptr);
        EXPECT_LT(phi.cwiseAbs().maxCoeff(), 1e-12);
      }
    }
  }
}

TEST(SpatialJoints, TheTranslationDriverPrescribesTheSlideAlongTheAxis) {
  std::mt19937 rng(9);
  Assembly as(rng);
  const auto law = std::make_shared<RampLaw>(0.0, 2.0, 0.5);  // s = 2 t² (t ≤ 0.5)
  const auto drv =
      make_spatial_translation_driver(SpatialBody{0}, as.A, SpatialBody{12}, as.B, as.f, law);
  const double t = 0.3, s = law->value(t);
  SpatialPose B = as.B;
  B.r += s * as.f.axes.col(2) + 0.2 * as.f.axes.col(0);  // the driver ignores the other axes
  B.write(12, as.q);
  LocalEqVec phi;
  drv->evaluate(t, gather(*drv, as.q), ModelParams{}, phi, nullptr);
  EXPECT_LT(std::abs(phi[0]), 1e-12);
  const LocalVec z = gather(*drv, as.q) + checks::random_local(24, rng, 0.3);
  const auto e = checks::check_constraint(*drv, t, z, checks::random_local(1, rng));
  EXPECT_LT(e.jacobian, 1e-8);
  EXPECT_LT(e.hessian, 1e-8);
  EXPECT_LT(e.time, 1e-7);
}

TEST(SpatialLoads, TangentsAndParameterDerivativesAgainstCentralDifferences) {
  std::mt19937 rng(13);
  const auto law = [](double v) { return std::make_shared<ConstantLaw>(v); };
  ModelParams p;
  p.scalars = {1.7, 300.0, 4.0, 0.25};  // load scale; spring k, c, l0
  using L = SpatialLoad;
  for (const auto kind : {L::Kind::kForce, L::Kind::kTorque}) {
    for (const auto frame : {L::Frame::kGround, L::Frame::kBody}) {
      const SpatialLoad load(0, kind, frame, random_vec(rng),
                             {law(3.0), law(-2.0), std::make_shared<RampLaw>(0.5, 4.0, 1.0)}, 0,
                             "load");
      LocalState s;
      s.t = 0.4;
      s.q = checks::random_local(12, rng), s.v = checks::random_local(12, rng);
      s.a = checks::random_local(12, rng);
      const auto e = checks::check_force(load, s, p);
      EXPECT_LT(e.stiffness, 1e-8);
      EXPECT_LT(e.damping, 1e-12);
      EXPECT_LT(e.mass, 1e-12);
      EXPECT_LT(e.parameters, 1e-8);
    }
  }
  for (int ground = 0; ground < 2; ++ground) {
    const SpatialSpringDamper spring(SpatialBody{0}, random_vec(rng), SpatialBody{ground ? -1 : 12},
                                     random_vec(rng), 1, 2, 3, "spring");
    const int n = ground ? 12 : 24;
    LocalState s;
    s.q = checks::random_local(n, rng), s.v = checks::random_local(n, rng);
    s.a = checks::random_local(n, rng);
    const auto e = checks::check_force(spring, s, p);
    EXPECT_LT(e.stiffness, 1e-6);
    EXPECT_LT(e.damping, 1e-6);
    EXPECT_LT(e.mass, 1e-12);
    EXPECT_LT(e.parameters, 1e-6);
  }
}

TEST(SpatialLoads, PowerOnARigidMotionIsForceTimesVelocityAndTorqueTimesSpin) {
  std::mt19937 rng(17);
  const auto law = [](double v) { return std::make_shared<ConstantLaw>(v); };
  ModelParams p;
  p.scalars = {1.3};
  const SpatialPose P = {random_vec(rng), random_rotation(rng)};
  const Vec3 d = random_vec(rng), L(3.0, -2.0, 0.7), omega = random_vec(rng, 3),
             v = random_vec(rng, 2);
  Vec q = Vec::Zero(12), qdot = Vec::Zero(12);
  P.write(0, q);
  twist_rates(P, omega, v, P.r, qdot, 0);  // v: the velocity of the centre of mass
  using S = SpatialLoad;
  for (const auto kind : {S::Kind::kForce, S::Kind::kTorque}) {
    for (const auto frame : {S::Frame::kGround, S::Frame::kBody}) {
      const SpatialLoad load(0, kind, frame, d, {law(L[0]), law(L[1]), law(L[2])}, 0, "load");
      LocalState s;
      s.q = q, s.v = qdot, s.a = LocalVec::Zero(12);
      LocalVec r = LocalVec::Zero(12);
      load.evaluate(s, p, r, nullptr, nullptr);
      const Vec3 W = 1.3 * (frame == S::Frame::kBody ? Vec3(P.R * L) : L);
      const double power = kind == S::Kind::kForce ? W.dot(v + omega.cross(P.R * d)) : W.dot(omega);
      EXPECT_NEAR(-r.dot(s.v), power, 1e-12 * (1 + std::abs(power)));
    }
  }
}

TEST(SpatialLoads, TheSpringLengthIsTheDistanceBetweenItsPoints) {
  std::mt19937 rng(19);
  const SpatialPose A = {random_vec(rng), random_rotation(rng)},
                    B = {random_vec(rng), random_rotation(rng)};
  const Vec3 da = random_vec(rng), db = random_vec(rng);
  Vec q = Vec::Zero(24);
  A.write(0, q);
  B.write(12, q);
  const SpatialSpringDamper spring(SpatialBody{0}, da, SpatialBody{12}, db, 0, -1, 0, "s");
  EXPECT_NEAR(spring.length(q), ((B.r + B.R * db) - (A.r + A.R * da)).norm(), 1e-14);
}
