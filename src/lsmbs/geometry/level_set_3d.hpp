#pragma once
// Level-set features of 3D solid bodies (docs/methods.md, "3D level sets"), the spatial
// counterpart of feature.hpp / level_set.hpp: each feature gives a signed distance D(x) with
// D > 0 outside its shape (the paper's hole form, §2.2); hole = false makes it a solid inclusion
// (−D). Parameters are affine in the design variables (ParamBinding), and ∂D/∂θ is exact
// (forward-mode duals, dual.hpp).
//   sphere:           D = |x − c| − r                                   params cx, cy, cz, r
//   cylinder:         D = |(x − c) − ((x − c)·a) a| − r, and with a length L > 0 the capped
//                     cylinder max(D, |(x − c)·a| − L/2)                params cx, cy, cz, r,
//                     length (axis a: the frame's third column; length 0: through everything)
//   super_ellipsoid:  g = (|u/a|^ξ + |v/b|^ξ + |w/c|^ξ)^(1/ξ), (u, v, w) = Aᵀ(x − c),
//                     D = (g − 1)/|∇g| (first order)                   params cx, cy, cz, a, b, c,
//                     xi
//   pocket:           a planar profile (a circle, ellipse or super-ellipse of feature.hpp, its
//                     parameters in the face frame's (u, v)) machined to a depth from a face:
//                     D = max(D₂(u, v), w − depth), (u, v, w) = Aᵀ(x − o), w into the part
//                                                                        params: the profile's,
//                                                                        depth
//   through_hole:     the profile through the whole part along the frame's w: D = D₂(u, v)
// The frame (origin o, axes A = [u v w], orthonormal) is data, not a design parameter.
//
// Distances. Spheres and cylinders (infinite ones) are exact; a capped cylinder and a pocket are
// the max of two exact distances: exact inside the void and a lower bound on the distance
// outside it (the void lies within either set). A super-ellipsoid's D is first order; for
// ξ ≥ 2 (required) it is a lower bound outside (g is convex and homogeneous), and inside the
// distance is at least (1 − g)·min(a, b, c) (g is 1/min(a, b, c)-Lipschitz): bound() returns
// these, which lets the mapping call an element uniform only where no boundary can reach it.
// A super-ellipse profile's D₀ = φ/|∇φ| (feature.hpp) is no distance (it grows without bound
// towards the centre): bound() takes the ball of radius ρ about x that the caller asks about and
// gives sign(L)(|L| + ρ) from the profile's lower bound L of |D₀| over that disc
// (Feature::far_bound), where |L| reaches the refinement radius (so distance() is D₀ there),
// else 0 (no claim).
#include <string>
#include <vector>

#include "lsmbs/core/types.hpp"
#include "lsmbs/geometry/csg.hpp"
#include "lsmbs/geometry/dual.hpp"
#include "lsmbs/geometry/feature.hpp"

namespace lsmbs {

/// A feature's frame: origin and orthonormal axes (columns u, v, w) in the body's coordinates.
struct Frame3 {
  Vec3 origin = Vec3::Zero();
  Mat3 axes = Mat3::Identity();
};

class Feature3 {
 public:
  enum class Type { kSphere, kCylinder, kSuperEllipsoid, kPocket, kThroughHole };
  /// `profile` is the planar feature type of a pocket or a through-hole (circle, ellipse or
  /// super_ellipse); `params` lists the profile's parameters then, for a pocket, the depth.
  Feature3(std::string name, Type type, std::vector<ParamBinding> params, bool hole,
           Frame3 frame = {}, Feature::Type profile = Feature::Type::kCircle);

  static Type parse_type(const std::string& s, bool* ok);
  static const std::vector<std::string>& type_names();
  /// The parameters' names of a type (a pocket's and a through-hole's follow the profile).
  static std::vector<std::string> parameter_names(Type t, Feature::Type profile);
  const std::string& name() const { return name_; }
  Type type() const { return type_; }
  bool hole() const { return hole_; }
  const Frame3& frame() const { return frame_; }
  Feature::Type profile() const { return profile_.type(); }
  const std::vector<ParamBinding>& params() const { return params_; }
  std::vector<double> values(const Vec& p) const;
  /// Empty if the parameter values θ describe a valid feature, else what is wrong.
  std::string check(const std::vector<double>& theta) const;

  /// The signed distance estimate D(x) (hole form: > 0 outside the shape), with T = double or
  /// Dual over the parameters. `refine_within`: a profile's distances below it are refined to
  /// third order (Feature::distance).
  template <class T>
  T distance(const Vec3& x, const T* theta, double refine_within) const;
  /// A signed value B with the sign of distance() at x such that, where |B| > ρ + t for a t ≥ 0,
  /// distance() keeps that sign and exceeds t in magnitude over the ball of radius ρ about x (an
  /// exact distance itself; see the header).
  double bound(const Vec3& x, const double* theta, double refine_within, double rho) const;

 private:
  std::string name_;
  Type type_;
  std::vector<ParamBinding> params_;
  bool hole_;
  Frame3 frame_;
  Feature profile_;  // a pocket's or a through-hole's planar shape (hole form)
};

/// Features of one solid body combined by the Boolean tree of csg.hpp.
class LevelSet3 {
 public:
  using Gradient = LevelSetGradient;
  LevelSet3() = default;
  LevelSet3(std::vector<Feature3> features, LevelSetNode root, int num_variables);
  const std::vector<Feature3>& features() const { return features_; }
  const LevelSetNode& root() const { return root_; }
  int num_variables() const { return nv_; }
  /// Parameter values of every feature at design p (call once per design).
  std::vector<std::vector<double>> values(const Vec& p) const;
  /// D(x); if grad is non-null it is cleared and receives ∂D/∂p.
  double evaluate(const Vec3& x, const std::vector<std::vector<double>>& theta,
                  Gradient* grad) const;
  /// The tree over the features' bound(): where |bound| exceeds a length, no boundary lies
  /// within it (up to slack(): a KS-smoothed min/max lies below the exact one by up to
  /// ln(children)/ks).
  double bound(const Vec3& x, const std::vector<std::vector<double>>& theta, double rho) const;
  /// Whether an exact min/max of the tree has two children within tol of each other at x whose
  /// derivatives differ (coinciding features: a kink of D in p; LevelSet::tie_at).
  bool tie_at(const Vec3& x, const std::vector<std::vector<double>>& theta, double tol) const;
  double slack() const { return slack_; }
  void set_refine_within(double d) { refine_within_ = d; }

 private:
  double feature_distance(int f, const Vec3& x, const std::vector<std::vector<double>>& theta,
                          Gradient* grad) const;
  std::vector<Feature3> features_;
  LevelSetNode root_;
  int nv_ = 0;
  double refine_within_ = 0, slack_ = 0;
};

}  // namespace lsmbs
