#pragma once
// Pieces the planar and the solid length-scale measures share (length_scale.hpp,
// solid_length_scale.hpp): the exact signed distance to a planar feature's shape, the disc that
// holds it, the KS aggregate of sampled values, and a feature's member size.
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "lsmbs/geometry/csg.hpp"
#include "lsmbs/geometry/feature.hpp"
#include "lsmbs/geometry/length_scale.hpp"

namespace lsmbs::length_scale_parts {

/// The super-ellipse quadrant (a cos^(2/ξ) t, b sin^(2/η) t), t ∈ [0, π/2], tabulated at 129
/// points; foot() is the closest point to y ≥ 0 (componentwise): the nearest tabulated point,
/// then a golden-section search for the least squared distance between its neighbours (the
/// distance exact to round-off, the foot to ~1e-10 of the semi-axes).
struct QuarterArc {
  static constexpr int kPoints = 128;
  double a, b, xi, eta;
  std::array<Vec2, kPoints + 1> table;
  QuarterArc(double a_, double b_, double xi_, double eta_);
  static double step();
  Vec2 at(double t) const;
  Vec2 foot(const Vec2& y) const;
};

/// The table of a super-ellipse's quadrant at parameter values th (a dummy for other types).
QuarterArc arc_of(Feature::Type type, const std::vector<double>& th);

/// The exact signed distance from x to the shape of planar feature f (> 0 outside the closed
/// curve, whether the feature is a hole or a solid) at parameter values th; not for B-splines.
/// With T = Dual its derivatives by the envelope theorem: ∂s/∂θ = (∂φ/∂θ)(y*) / |∇φ(y*)| at the
/// closest point y*. `arc`: the super-ellipse's table at th (null: tabulated here).
template <class T>
T shape_distance(const Feature& f, const Vec2& x, const T* th, const QuarterArc* arc);

/// Centre of a disc that holds the feature's shape: (cx, cy), or a B-spline's control points'
/// mean (the curve lies in their convex hull).
Vec2 centre(const Feature& f, const std::vector<double>& th);
/// Radius of that disc.
double reach(const Feature& f, const std::vector<double>& th);

/// KS lower envelope of the values v_k: m − (1/ρ) ln Σ exp(−ρ (v_k − m)) and each value's weight.
double ks_min(const std::vector<double>& v, double rho, std::vector<double>& w);

/// The KS minimum of v_k = d_i[k] (+ d_j[k] when dj is given) over the samples k with use[k]
/// (all when `use` is empty) whose v_k lies below `cap`.
struct SampledMinimum {
  bool any = false;  ///< a sample below the cap
  double value = 0;
  size_t argmin = 0;                               ///< the sample of the least v_k
  std::vector<std::pair<size_t, double>> weights;  ///< samples and their weights (> 1e-16)
};
SampledMinimum sampled_minimum(const std::vector<double>& di, const std::vector<double>* dj,
                               const std::vector<char>& use, double cap, double rho);

/// A planar shape's width, twice its inscribed radius (−s at its centre): 2r (circle), the KS
/// minimum of 2ad and 2bd (ellipse, eq. 41) or of 2a and 2b (super-ellipse with ξ, η ≥ 2, eq. 43),
/// with ρ = ln 2/(tolerance · δ). `params` bind the shape's parameters θ (values th) to the nv
/// design variables; `at` is left at (cx, cy).
LengthScaleConstraint member_size(const std::string& name, Feature::Type type,
                                  const std::vector<ParamBinding>& params,
                                  const std::vector<double>& th, double delta, double tolerance,
                                  int nv);

/// Per feature: whether it bounds void in the region `root` — a hole (hole()) under an even
/// number of NOTs, or a solid under an odd number (NOT turns a hole's void into material).
template <class Feat>
std::vector<char> void_features(const LevelSetNode& root, const std::vector<Feat>& features) {
  std::vector<char> negated(features.size(), 0);
  auto walk = [&](const LevelSetNode& n, bool neg, const auto& self) -> void {
    if (n.op == LevelSetNode::Op::kFeature && n.feature >= 0 &&
        n.feature < static_cast<int>(negated.size()))
      negated[static_cast<size_t>(n.feature)] = neg;
    for (const auto& c : n.children) self(c, neg != (n.op == LevelSetNode::Op::kNot), self);
  };
  walk(root, false, walk);
  std::vector<char> v(features.size());
  for (size_t i = 0; i < features.size(); ++i) v[i] = features[i].hole() != (negated[i] != 0);
  return v;
}

/// The constraints' names in evaluate()'s order: per void design feature its ligaments (to the
/// later void features and the non-design regions), its edge and, planar only, its no_cut; then
/// every design feature's member size.
template <class Feat>
std::vector<std::string> constraint_names(const std::vector<Feat>& F,
                                          const std::vector<char>& voids, int num_design,
                                          const LengthScaleOptions& o) {
  std::vector<std::string> n;
  for (int i = 0; i < num_design; ++i) {
    if (!voids[static_cast<size_t>(i)]) continue;
    if (o.min_ligament > 0)
      for (int j = i + 1; j < static_cast<int>(F.size()); ++j)
        if (j >= num_design || voids[static_cast<size_t>(j)])
          n.push_back("ligament." + F[static_cast<size_t>(i)].name() + "." +
                      F[static_cast<size_t>(j)].name());
    if (o.min_edge > 0) n.push_back("edge." + F[static_cast<size_t>(i)].name());
    if (o.no_cut > 0) n.push_back("no_cut." + F[static_cast<size_t>(i)].name());
  }
  if (o.min_member > 0)
    for (int i = 0; i < num_design; ++i) n.push_back("member." + F[static_cast<size_t>(i)].name());
  return n;
}

}  // namespace lsmbs::length_scale_parts
