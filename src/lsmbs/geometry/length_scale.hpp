#pragma once
// Length-scale constraints of a feature-based design (docs/designs.md, "Length-scale control"):
// geometric measures of one body's level set, each a smooth function of the design variables
// with its exact gradient, bounded below by a length δ. With D_i the signed distance of feature i
// (Feature::distance: > 0 in material, exact for ellipses and circles, refined to third order for
// super-ellipses), and the body sampled on a grid of spacing s inside its mesh and along its
// boundary loops:
//   - ligament between design features i and j (and between a design feature and a non-design
//     region, whose distance is that of its solid from outside): min_x (D_i(x) + D_j(x)) over the
//     grid, which is the distance between the two shapes (the minimum of d(x, A) + d(x, B) is
//     d(A, B), taken on the segment of the nearest points); negative where they overlap;
//   - edge ligament of a design feature: min over the boundary samples x_b of D_i(x_b), the
//     distance from the feature to the body's edges (outer and inner loops);
//   - no cut: a feature may reach the boundary in one place (a notch) but leaves at least δ
//     everywhere else: the minimum of D_i over the boundary samples outside the run of samples
//     closer than δ around its deepest one;
//   - member size of a feature: twice its inscribed radius, −2 D_i at its centre: 2r (circle),
//     2d·min(a, b) (ellipse, eq. 41), 2 min(a, b) (super-ellipse with ξ, η ≥ 2, eq. 43); none
//     for a closed B-spline (a free-form hole has no centre: the member size is refused).
// A closed B-spline's distance is its exact distance to the curve (ClosedBSpline) with the sparse
// derivatives of LevelSet::feature_distance; the sampled measures above hold for it unchanged.
// Each minimum is a KS aggregate KS(v) = m − (1/ρ) ln Σ_k exp(−ρ (v_k − m)), m = min v_k, which
// lies below the minimum by at most ln(N)/ρ (N samples): a design with KS ≥ δ has every sample
// ≥ δ, conservative by at most that much. ρ = ln(N)/(tolerance · δ) makes the bound the fraction
// `tolerance` of δ. The sampling adds to a ligament at most about s²/(8R) (R: the smaller radius
// of curvature of the two boundaries at their nearest points: the sum of distances is flat along
// the segment between them and quadratic across it), and as much to an edge ligament.
// Samples farther than 3δ_max from a feature (by its enclosing disc; δ_max the largest of the
// bounds) are not evaluated: a measure larger than 3δ_max is reported as 3δ_max with a zero
// gradient (the bound holds there with room; `at` is the feature's centre when no sample is
// within reach).
// no_cut on a non-convex feature (a B-spline) that nears one edge at two places keeps δ at the
// shallower one: breaking through both would cut off the material between them.
#include <string>
#include <vector>

#include "lsmbs/fem/mesh.hpp"
#include "lsmbs/geometry/level_set.hpp"

namespace lsmbs {

struct LengthScaleOptions {
  double min_ligament = 0;  ///< [m] between two features, or a feature and a non-design region
  double min_edge = 0;      ///< [m] between a feature and the body's boundary
  double min_member = 0;    ///< [m] a feature's own width
  double no_cut = 0;        ///< [m] material a feature leaves on the boundary outside one notch
  double tolerance = 0.05;  ///< KS aggregation error bound, as a fraction of each bound δ
  double spacing = 0;       ///< sampling grid [m]; 0: a quarter of the median element size
  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

/// One constraint value ≥ bound.
struct LengthScaleConstraint {
  std::string kind;           ///< ligament | edge | no_cut | member
  std::string first, second;  ///< feature names (second empty for edge, no_cut, member)
  double bound = 0;           ///< δ [m]
  double value = 0;           ///< the aggregated measure [m]
  double error_bound = 0;     ///< value ≥ (true minimum) − error_bound, value ≤ true minimum
  Vec gradient;               ///< ∂value/∂p
  Vec at;                     ///< where the measure is smallest (2 or 3 coordinates)
  std::string name() const;   ///< "ligament.LS1.LS2", "edge.LS1", "member.LS1", …
};

/// The length-scale measures of one body's design: LengthScale (planar) or SolidLengthScale
/// (solid_length_scale.hpp).
class LengthScaleMeasures {
 public:
  virtual ~LengthScaleMeasures() = default;
  /// The constraints at design p, in a fixed order (their names do not depend on p).
  std::vector<LengthScaleConstraint> evaluate(const Vec& p) const;
  /// Names of the constraints evaluate() returns.
  std::vector<std::string> names() const;
  /// The sampling's spacing [m].
  virtual double spacing() const = 0;
  /// Leaves out the ligaments between features that overlap at design p (a negative ligament):
  /// they form one void by design (a counterbore, a lens of two holes, an OR of two voids), which
  /// no bound could part without changing the design's topology. Returns their names.
  std::vector<std::string> leave_out_overlaps(const Vec& p);
  const std::vector<std::string>& left_out() const { return left_out_; }

 protected:
  virtual std::vector<LengthScaleConstraint> evaluate_all(const Vec& p) const = 0;
  virtual std::vector<std::string> all_names() const = 0;

 private:
  std::vector<std::string> left_out_;
};

class LengthScale final : public LengthScaleMeasures {
 public:
  /// Features [0, num_design) of `ls` are the design features, the others non-design regions.
  LengthScale(const Mesh2D& mesh, const LevelSet& ls, int num_design, LengthScaleOptions o);
  double spacing() const override { return spacing_; }

 protected:
  std::vector<LengthScaleConstraint> evaluate_all(const Vec& p) const override;
  std::vector<std::string> all_names() const override;

 private:
  struct Sample {
    Vec2 x;
    int loop = -1;  ///< boundary samples: their loop (in order along it); grid samples: −1
  };
  const LevelSet* ls_;
  int nd_ = 0;
  std::vector<char> void_;  ///< per feature: bounds void (a hole not under an odd number of NOTs)
  LengthScaleOptions o_;
  double spacing_ = 0;
  std::vector<Sample> grid_, boundary_;
};

}  // namespace lsmbs
