#pragma once
// The shape of a designed body as data for CAD and meshing tools (python/lsmbs/export.py: DXF,
// SVG, STEP, a body-fitted Gmsh mesh): in the body's own (mesh) frame, in metres,
//   outline    the mesh's boundary loops (outer counter-clockwise, holes clockwise), polygons
//              through the boundary nodes: exact for straight edges, chords of curved ones;
//   features   each level-set feature with its parameter values at the design (eqs. 41, 43),
//              its kind (hole or solid) and its exact boundary in words ("circle", "ellipse",
//              "super_ellipse");
//   region     the Boolean combination (and = min, or = max, not; ks > 0: the KS smoothing of
//              that combination, which CAD Booleans replace by the exact one);
//   node_sets  every node set's node positions (the joints' connections), so that a body-fitted
//              mesh can name the same sets;
//   thickness, material, element_size (median √area of the fixed mesh's elements).
#include <nlohmann/json.hpp>

#include "lsmbs/design/design.hpp"

namespace lsmbs {

nlohmann::json shape_json(const BodyDesign& b, const Vec& p, const ModelParams& params);

/// A designed solid body's shape ("kind": "solid"), in ground coordinates at t = 0, in metres:
///   domain    {"type": "box", "lo", "hi"} when the mesh fills its bounding box (a box mesh),
///             else {"type": "mesh"} (the part's own surface is not known as CAD);
///   features  each 3D feature (level_set_3d.hpp) with its parameter values at the design, its
///             kind (hole or solid), its frame (origin, axes as the columns u, v, w) and a
///             pocket's or through-hole's planar profile type;
///   region    as for planar shapes; material, mu_min.
nlohmann::json solid_shape_json(const SolidBodyDesign& b, const Vec& p, const ModelParams& params);

}  // namespace lsmbs
