#pragma once
// What the fixed mesh resolves of a solid body's 3D design, the geometric half of judging it
// (resolution.hpp for planar bodies), from the length-scale measures of solid_length_scale.hpp
// taken at a KS tolerance of 0.1 % (so each value is the sampled minimum to 0.1 % of the
// threshold). A part is resolved when it is min_elements cells wide measured across it: its
// threshold is min_elements times the extent of the cell at its narrowest point along the
// direction across it, so a pocket's floor is judged against the cells' thickness and a
// ligament in a plate against their length.
//   - each ligament between two void features narrower than 3 thresholds, across it along
//     ∇s_i − ∇s_j (off the segment between the nearest points the two gradients tilt in opposite
//     directions: their difference keeps to it). Features that overlap (a negative ligament)
//     have merged into one void: no part;
//   - each void feature's flange to each face of the body it does not open (its boundary samples
//     grouped by their normals), across the face: a pocket's floor, and the flanges of a hole that
//     breaks through another face (a notch, not itself a part);
//   - each void feature's width (member size), along its narrowest direction from its centre (in
//     the profile's plane for pockets and through-holes; of directions as narrow, the one across
//     which the cell is thinnest);
//   - the pieces the material falls into: the volume samples in material (level set > 0)
//     connected to those within √3 spacings when the level set at the midpoint is in material
//     too; material joined by less than the spacing counts as cut. Volumes are the samples' shares
//     of their cells; pieces smaller than half the median cell are left out.
// A feature is judged only where it bounds void: where it is the level set's active leaf at its
// zero (a hole inside another, in an OR of holes or wholly outside the body bounds none). Solid
// (hole = false) design features and non-design regions are material, not measured.
#include "lsmbs/fem/solid_mesh.hpp"
#include "lsmbs/geometry/level_set_3d.hpp"
#include "lsmbs/geometry/resolution.hpp"

namespace lsmbs {

/// The resolution of design p of the 3D level set `ls` (features [0, num_design) are the design
/// features) on `mesh`; element_size is the median longest cell edge, the sampling's spacing
/// element_size / samples_per_element.
ResolutionReport judge_solid_resolution(const SolidMesh& mesh, const LevelSet3& ls, int num_design,
                                        const Vec& p, const ResolutionOptions& o = {});

}  // namespace lsmbs
