#pragma once
// SolidDesignMap — the 3D level set of a solid body mapped onto its fixed mesh as element volume
// fractions, the spatial counterpart of DesignMap (eqs. 3–5):
//   μ_e = μ_min + (1 − μ_min) (1/V_e) ∫_e H*(D(x)) dV,  H*(D) = 1 / (1 + exp(−D/ε)),
//   ∂μ_e/∂p = (1 − μ_min)/V_e Σ_s w_s H*'(D_s) ∂D_s/∂p  (exact; sparse).
// Cut elements are integrated on n × n × n sub-cells: a hexahedron's parent cube [−1, 1]³ mapped
// trilinearly (weight det J × (2/n)³ at each sub-cell centre), a tetrahedron's through the
// collapsed cube (Duffy) map, (a, b, c) ∈ [0, 1]³ → λ = (a, b(1 − a), c(1 − a)(1 − b)), each
// sub-cell weighted by its exact volume. V_e is the sum of the weights, so a uniform element has
// μ_e = 1 exactly. ε = band × (median longest element edge / n): the band spans `band` sub-cells
// in every direction, also of a flat element. An element is uniform (μ_e = 1 or μ_min,
// not integrated) when the level set's bound() at its centre exceeds its circumradius + 30 ε
// (+ the KS slack): no boundary can reach it.
#include <vector>

#include "lsmbs/fem/solid_mesh.hpp"
#include "lsmbs/geometry/design_map.hpp"
#include "lsmbs/geometry/level_set_3d.hpp"

namespace lsmbs {

class SolidDesignMap {
 public:
  /// MappingOptions::offset must be 0 (the eroded and dilated designs are planar only).
  SolidDesignMap(const SolidMesh& mesh, LevelSet3 level_set, MappingOptions opt);
  const LevelSet3& level_set() const { return ls_; }
  const MappingOptions& options() const { return opt_; }
  double epsilon() const { return eps_; }
  int num_elements() const { return static_cast<int>(volume_.size()); }
  /// The elements' volumes (2 × 2 × 2 Gauss for hexahedra: exact for trilinear ones).
  const std::vector<double>& element_volumes() const { return volume_; }
  /// μ (size n_e) and, if requested, ∂μ/∂p (n_e × n_v, sparse) and the counts of the mapping.
  /// A pure function of p.
  void map(const Vec& p, Vec& mu, SpMat* dmu_dp = nullptr, MapCounts* counts = nullptr) const;
  /// Features (indices into level_set().features()) wholly outside the mesh at p: every element's
  /// centre is farther from the feature's shape than the element's circumradius (the features'
  /// bound(), never above the true distance).
  std::vector<int> features_outside_mesh(const Vec& p) const;
  /// Material volume Σ_e V_e (μ_e − μ_min)/(1 − μ_min) and its gradient (checks and reports).
  double material_volume(const Vec& mu, const SpMat* dmu, Vec* grad) const;

 private:
  // The sub-cell centres and weights of element e.
  void subcells(int e, std::vector<Vec3>& x, std::vector<double>& w) const;
  const SolidMesh* mesh_;
  LevelSet3 ls_;
  MappingOptions opt_;
  double eps_ = 0;
  std::vector<double> volume_, radius_;
  std::vector<Vec3> centre_;
};

}  // namespace lsmbs
