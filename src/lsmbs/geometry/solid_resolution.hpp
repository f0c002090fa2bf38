#pragma once
// What the fixed mesh resolves of a solid body's 3D design, the geometric half of judging it
// (resolution.hpp for planar bodies), from the length-scale measures of solid_length_scale.hpp
// taken at a KS tolerance of 0.1 % (so each value is the sampled minimum to 0.1 % of the
// threshold):
//   - each ligament between two void features, and between a void feature and the faces it is
//     not meant to open (a pocket's floor included), narrower than 3 thresholds: its width, where
//     it is narrowest, and whether the cell there resolves it. A part is resolved when it is
//     min_elements cells wide measured across it: the threshold is min_elements times the extent
//     of the cell at its narrowest point along the direction across it (∇s_i there), so a pocket's
//     floor is judged against the cells' thickness and a ligament in a plate against their
//     length. Features that overlap (a negative ligament) have merged into one void: no part;
//   - each void feature's width (member size) against the cells' extent along its narrowest
//     direction (probed from its centre; in the profile's plane for pockets and through-holes);
//   - the pieces the material falls into: the volume samples in material (level set > 0)
//     connected to those within √3 spacings when the level set at the midpoint is in material
//     too; material joined by less than the spacing counts as cut. Volumes are the samples' shares
//     of their cells; pieces smaller than half the median cell are left out.
// Solid (hole = false) design features are not measured (as by the length-scale constraints).
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
