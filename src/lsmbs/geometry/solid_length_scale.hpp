#pragma once
// Length-scale constraints of a solid body's 3D feature design (docs/designs.md, "Length-scale
// control"), the spatial counterpart of length_scale.hpp: each a smooth function of the design
// variables with its exact gradient, bounded below by a length δ. With s_i(x) the signed
// distance from x to the shape of feature i (> 0 outside it), the body is sampled at the centres
// of sub-cells of its cells (volume samples) and at the lattice points of the sub-cells of the
// faces no other cell shares, edges and corners included (boundary samples, each with its
// outward normal n), spacing s:
//   - ligament between design features i and j (and between a design feature and a non-design
//     region): min over the volume samples of s_i + s_j, the distance between the two shapes;
//   - edge ligament of a design feature: min of s_i over the boundary samples of the faces it is
//     not meant to open. A through-hole (or a cylinder of length 0) opens the faces its axis
//     leaves the body through, a pocket the face its axis enters through: at design p, the
//     boundary samples nearest the axis line among those facing +a and among those facing −a
//     (a pocket: facing −w, short of half its depth) anchor those faces, and the samples whose
//     normals lie within 45° of an anchor's are left out. So a pocket's edge ligament includes its
//     floor, the material under it, and a tilted through-hole that breaks through a side face makes
//     its edge ligament negative;
//   - member size: a sphere's 2r, a cylinder's 2r (with a length L: the KS minimum of 2r and L),
//     a super-ellipsoid's KS minimum of 2a, 2b, 2c, and a pocket's or a through-hole's profile's
//     width (length_scale.hpp); a pocket's depth is not a width.
// Distances s_i are exact for spheres, cylinders (capped ones as the distance to a solid of
// revolution: √(d_r² + d_z²) off the corner's region), pockets and through-holes (the planar
// profile's exact distance, super-ellipses included, extruded: the distance to a product of sets
// is the root sum of squares of the factors' distances), and super-ellipsoids outside them (the
// closest point by nested monotone root-finding); inside a super-ellipsoid s is the lower bound
// (g − 1)·min(a, b, c) on its depth (a ligament's minimum lies outside both shapes).
// Features that bound void are the holes not under an odd number of NOTs of the region (and
// solids under one); ligaments between features that overlap at the initial design are left out
// by the caller (LengthScaleMeasures::leave_out_overlaps).
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
  double spacing() const override { return spacing_; }
  int num_volume_samples() const { return static_cast<int>(volume_.size()); }
  int num_boundary_samples() const { return static_cast<int>(boundary_.size()); }
  /// Volume sample k and its share of its cell's volume [m³] (the shares sum to the cell's).
  const Vec3& volume_sample(int k) const { return volume_[static_cast<size_t>(k)].x; }
  double volume_weight(int k) const { return volume_[static_cast<size_t>(k)].w; }
  /// s_i(x): the distance from x to feature i's shape (> 0 outside it) at parameter values
  /// theta (LevelSet3::values).
  double shape_distance(int i, const Vec3& x, const std::vector<std::vector<double>>& theta) const;
  /// Feature i's least distance to each face of the body it does not open (the edge ligament's
  /// boundary samples grouped by their normals, each group within 45° of its first sample's),
  /// where it lies and the face's normal there; groups whose samples are all farther than `cap`
  /// (by a cheap lower bound) are left out.
  struct FaceDistance {
    double value = 0;
    Vec3 at = Vec3::Zero(), normal = Vec3::Zero();
  };
  std::vector<FaceDistance> face_distances(int i, const std::vector<std::vector<double>>& theta,
                                           double cap) const;

 protected:
  std::vector<LengthScaleConstraint> evaluate_all(const Vec& p) const override;
  std::vector<std::string> all_names() const override;

 private:
  struct Sample {
    Vec3 x;
    Vec3 n = Vec3::Zero();  ///< boundary samples: the outward unit normal
    double w = 0;           ///< volume samples: the sub-cell's volume
  };
  void sample_hexahedron(const SolidMesh& mesh, int e, const std::vector<char>& open_face);
  void sample_tetrahedron(const SolidMesh& mesh, int e, const std::vector<char>& open_face);
  // The boundary samples feature i's edge ligament keeps at its parameter values th (empty: all).
  std::vector<char> edge_samples(int i, const std::vector<double>& th) const;
  const LevelSet3* ls_;
  int nd_ = 0;
  std::vector<char> void_;  ///< per feature: bounds void (a hole not under an odd number of NOTs)
  LengthScaleOptions o_;
  double spacing_ = 0;
  std::vector<Sample> volume_, boundary_;
  std::vector<std::optional<Feature>> profile_;  ///< a pocket's or a through-hole's planar shape
  std::vector<int> face_group_;  ///< per boundary sample: its group of normals (face_distances)
};

}  // namespace lsmbs
