#pragma once
// Length-scale constraints of a solid body's 3D feature design (docs/designs.md, "Length-scale
// control"), the spatial counterpart of length_scale.hpp: each a smooth function of the design
// variables with its exact gradient, bounded below by a length δ. With s_i(x) the signed
// distance from x to the shape of feature i (> 0 outside it), the body is sampled at the centres
// of sub-cells of its cells (volume samples) and of the faces no other cell shares (boundary
// samples, each with its outward normal n), spacing s:
//   - ligament between design features i and j (and between a design feature and a non-design
//     region): min over the volume samples of s_i + s_j, the distance between the two shapes;
//   - edge ligament of a design feature: min of s_i over the boundary samples of the faces it is
//     not meant to open: a through-hole and a cylinder through the whole part leave out the faces
//     across their axis a (|n·a| ≥ 1/2), a pocket its entry face (n·w ≤ −1/2, w into the part);
//     so a pocket's edge ligament includes its floor, the material under it;
//   - member size: a sphere's 2r, a cylinder's 2r (with a length L: the KS minimum of 2r and L),
//     a super-ellipsoid's KS minimum of 2a, 2b, 2c, and a pocket's or a through-hole's profile's
//     width (length_scale.hpp); a pocket's depth is not a width.
// Distances s_i are exact for spheres, cylinders (capped ones as the distance to a solid of
// revolution: √(d_r² + d_z²) off the corner's region), pockets and through-holes (the planar
// profile's exact distance, super-ellipses included, extruded: the distance to a product of sets
// is the root sum of squares of the factors' distances); a super-ellipsoid's is its first-order
// estimate, a lower bound outside (ξ ≥ 2, level_set_3d.hpp), so its ligaments are conservative.
// The KS aggregate and its error bound are those of length_scale.hpp (N samples, ρ =
// ln N/(tolerance · δ)); sampling adds at most about s²/(8R) to a ligament. no_cut is planar only
// (a notch on a surface has no run of boundary samples to leave out): refused here.
#include <optional>
#include <string>
#include <vector>

#include "lsmbs/fem/solid_mesh.hpp"
#include "lsmbs/geometry/length_scale.hpp"
#include "lsmbs/geometry/level_set_3d.hpp"

namespace lsmbs {

class SolidLengthScale final : public LengthScaleMeasures {
 public:
  /// Features [0, num_design) of `ls` are the design features, the others non-design regions.
  /// `spacing` 0: a quarter of the median longest cell edge. Throws Error for o.no_cut > 0 or
  /// options that fail LengthScaleOptions::validate().
  SolidLengthScale(const SolidMesh& mesh, const LevelSet3& ls, int num_design,
                   LengthScaleOptions o);
  std::vector<LengthScaleConstraint> evaluate(const Vec& p) const override;
  std::vector<std::string> names() const override;
  double spacing() const override { return spacing_; }
  int num_volume_samples() const { return static_cast<int>(volume_.size()); }
  int num_boundary_samples() const { return static_cast<int>(boundary_.size()); }

 private:
  struct Sample {
    Vec3 x;
    Vec3 n = Vec3::Zero();  ///< boundary samples: the outward unit normal
  };
  void sample_hexahedron(const SolidMesh& mesh, int e, const std::vector<char>& open_face);
  void sample_tetrahedron(const SolidMesh& mesh, int e, const std::vector<char>& open_face);
  const LevelSet3* ls_;
  int nd_ = 0;
  LengthScaleOptions o_;
  double spacing_ = 0;
  std::vector<Sample> volume_, boundary_;
  std::vector<std::optional<Feature>> profile_;  ///< a pocket's or a through-hole's planar shape
  std::vector<std::vector<char>> edge_use_;      ///< per feature: the boundary samples it keeps
};

}  // namespace lsmbs
