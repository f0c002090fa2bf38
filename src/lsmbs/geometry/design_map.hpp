#pragma once
// DesignMap — the level set of one flexible body mapped onto its fixed mesh as element volume
// fractions (§2.3, eqs. 3–5):
//   μ_e = μ_min + (1 − μ_min) (1/V_e) ∫_e H*(D(x)) dV,   H*(D) = 1 / (1 + exp(−D/ε))   (eq. 5)
// Elements far from every boundary are uniform (μ_e = 1 or μ_min exactly); the others ("cut")
// are integrated on an n × n sub-grid of the element's parent domain with the exact level set
// at the sub-cell centres. The logistic band ε = band × (sub-cell size) is a physical length, so
// μ_e(p) is smooth and its derivative is non-zero exactly where a boundary passes:
//   ∂μ_e/∂p = (1 − μ_min)/V_e Σ_s w_s H*'(D_s) ∂D_s/∂p   (sparse: cut elements whose entry is
//   above 1e-12 of the column's largest).
// An element counts as uniform only if its corners and centre have the same sign and all lie
// farther than its circumradius + 30 ε from the boundary — a tiny hole inside one element (the
// p = 0.001 start of Table 1) is therefore still seen.
#include <vector>

#include "lsmbs/fem/mesh.hpp"
#include "lsmbs/geometry/level_set.hpp"

namespace lsmbs {

/// What a mapping met (diagnostics of run_geometry and verify).
struct MapCounts {
  /// Elements a boundary crosses: their corners, centre and sub-cell centres lie on both sides.
  int cut = 0;
  /// Elements integrated on the sub-grid: those within their circumradius + 30 ε of a boundary,
  /// the cut ones included (the cost of the mapping).
  int band = 0;
  /// (feature, element) pairs of the band whose feature was frozen at its centre value (far
  /// from the element: not evaluated on the sub-cells).
  long frozen = 0;
};

struct MappingOptions {
  double mu_min = 1e-3;
  int subgrid = 8;    ///< sub-cells per element edge in cut elements
  double band = 0.5;  ///< ε in units of the sub-cell size (median element size / subgrid)
  /// [m] the level set offset by this length: material where D > offset. > 0: the eroded design
  /// (holes grown by it), < 0: the dilated one; the robust formulation's variants of the design
  /// (docs/designs.md). The distances are refined to third order out to it (Feature::distance):
  /// exact for ellipses and circles, to the accuracy of three Newton projections for
  /// super-ellipses.
  double offset = 0;

  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

class DesignMap {
 public:
  DesignMap(const Mesh2D& mesh, LevelSet level_set, MappingOptions opt);
  const LevelSet& level_set() const { return ls_; }
  const MappingOptions& options() const { return opt_; }
  double epsilon() const { return eps_; }
  int num_elements() const { return static_cast<int>(area_.size()); }
  const std::vector<double>& element_areas() const { return area_; }

  /// μ (size n_e) and, if requested, ∂μ/∂p (n_e × n_v, sparse) and the counts of the mapping.
  /// A pure function of p: mappings at different p may run at once.
  void map(const Vec& p, Vec& mu, SpMat* dmu_dp = nullptr, MapCounts* counts = nullptr) const;
  /// Features (indices into level_set().features()) that lie wholly outside the mesh at p:
  /// every element's centre is farther from the feature's shape than the element's circumradius,
  /// so the feature overlaps no element (a hole drawn off the part, or in another frame or unit;
  /// only the logistic's tail, within a few bands of the mesh's edge, can still reach μ_e). The
  /// features' own distances are used: exact for ellipses and circles, below the true distance
  /// for super-ellipses (convex), so a feature that overlaps an element is never reported.
  std::vector<int> features_outside_mesh(const Vec& p) const;
  /// Whether a shape inside the disc of radius `radius` about some centre in the box
  /// [lo, hi] can overlap an element (the test of features_outside_mesh, taken over every such
  /// shape): false means no value of the design variables within their bounds brings it in.
  bool disc_can_reach_mesh(const Vec2& lo, const Vec2& hi, double radius) const;
  /// Whether map() freezes the features far from an element at their value at its centre (the
  /// default; false evaluates every feature everywhere, for the test that compares the two).
  void set_freeze_far_features(bool on) { freeze_far_features_ = on; }

 private:
  const Mesh2D* mesh_;
  LevelSet ls_;
  MappingOptions opt_;
  double eps_ = 0;
  bool freeze_far_features_ = true;
  std::vector<double> area_, radius_;
};

}  // namespace lsmbs
