#pragma once
// What the fixed mesh resolves of a design (the geometric half of judging a design): the level
// set of one body sampled on a grid finer than its mesh, and in the material there
//   - each ligament: the narrowest material between two boundaries, a feature's and another's or
//     the body's outer edge. At a material point x with distances r₁ ≤ r₂ to its two nearest
//     boundaries, x lies on their bisector when r₂ − r₁ ≤ the grid spacing, and the material
//     there is r₁ + r₂ wide; a ligament's width is the least such r₁ + r₂. A feature's boundary
//     counts only where it bounds void (its nearest point is on the zero contour of the whole
//     level set): a hole inside a non-design ring has the ring's outer edge as a boundary only
//     where the ring meets void.
//   - each hole's width: twice the largest distance from a void point inside it to its boundary
//     (the diameter of the largest disc it holds, within the mesh);
//   - the pieces the material falls into (connected points, 4-neighbours, of a grid 4× finer:
//     material joined by less than its spacing counts as cut).
// A ligament's width is exact to about one grid spacing (the bisector's sampling; the spacing is
// a quarter of the median element size by default); a hole's, refined by a pattern search from
// its deepest grid point, to the accuracy of the feature's distance (Feature::distance). The
// fixed-mesh mapping smears a boundary over the band of the elements it cuts (eq. 5), so a part
// narrower than about two elements is not a part the mesh resolves: its stiffness is that of partly
// filled elements.
#include <string>
#include <vector>

#include "lsmbs/fem/mesh.hpp"
#include "lsmbs/geometry/level_set.hpp"

namespace lsmbs {

struct ResolutionOptions {
  double min_elements = 2;      ///< parts narrower than this many median element sizes are flagged
  int samples_per_element = 4;  ///< grid points per median element size
};

/// The narrowest material between two boundaries (a ligament or a member), or a hole's width.
struct NarrowPart {
  enum class Kind { kLigament, kHole };
  Kind kind = Kind::kLigament;
  /// The boundaries on either side: feature names, or "outer edge" (a planar body's boundary),
  /// "surface" (a solid body's faces); a hole: its feature only.
  std::string first, second;
  double width = 0;  ///< [m]
  /// Where it is narrowest (a grid point on the bisector or in the hole; 2 or 3 coordinates).
  Vec at;
  /// The width the mesh resolves there [m]: min_elements element sizes (of a solid body: of the
  /// cell there, measured across the part).
  double threshold = 0;
  bool unresolved = false;  ///< narrower than threshold
};

struct ResolutionReport {
  double element_size = 0;  ///< median √(element area) [m]; of a solid: median longest edge
  double spacing = 0;       ///< of the sampling grid [m]; the widths' accuracy
  double threshold = 0;     ///< min_elements · element_size [m] (a part's own may differ: solids)
  std::vector<NarrowPart> parts;  ///< every ligament and hole found, narrowest first
  /// Areas (of a solid: volumes) of the connected pieces of material [m², m³], largest first
  /// (one piece: a whole body); pieces smaller than one element are left out.
  std::vector<double> pieces;
  double piece_spacing = 0;  ///< of the grid the pieces are found on [m]
  bool solid = false;        ///< a solid body's report (volumes, 3D positions)
  /// The parts narrower than the threshold, in words; empty when the mesh resolves the design.
  std::vector<std::string> flags() const;
  /// A body in more than one piece, in words; empty for one piece.
  std::string pieces_flag() const;
};

/// The resolution of the design whose level set is `ls` (feature values `v`) on `mesh`.
ResolutionReport judge_resolution(const Mesh2D& mesh, const LevelSet& ls, const LevelSet::Values& v,
                                  const ResolutionOptions& o = {});

}  // namespace lsmbs
