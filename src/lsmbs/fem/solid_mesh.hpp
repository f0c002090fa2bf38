#pragma once
// Meshes of 3D solid bodies: node positions, cells (eight-node hexahedra in the order of
// fem/hex_element.hpp, or four-node tetrahedra) and named node sets.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "lsmbs/core/types.hpp"

namespace lsmbs {

struct SolidMesh {
  std::vector<Vec3> nodes;
  std::vector<std::vector<int>> cells;  ///< 8 nodes (hexahedron) or 4 (tetrahedron) each
  std::map<std::string, std::vector<int>> node_sets;

  int num_nodes() const { return static_cast<int>(nodes.size()); }
  int num_elements() const { return static_cast<int>(cells.size()); }
  /// The largest extent of the bounding box.
  double size() const;
  /// "xmin, xmax, …" (or "no node sets"): what an error about a missing node set offers.
  std::string node_set_names() const;
  /// The box [origin, origin + size] in n[0] × n[1] × n[2] hexahedra, with the node sets of its
  /// six faces: xmin, xmax, ymin, ymax, zmin, zmax.
  static SolidMesh box(const Vec3& origin, const Vec3& size, const std::array<int, 3>& n);
  /// A Gmsh MSH 4.1 ASCII file (fem/msh_reader.hpp): its 4-node tetrahedra and 8-node hexahedra
  /// (Gmsh's node order is the hexahedron's), node sets from the physical groups of its points,
  /// lines and surface elements. A cell turned inside out as a whole is reordered; one folded in
  /// part, degenerate or nearly flat is refused with its tag and line, as are coincident nodes;
  /// nodes that no cell uses are dropped.
  static SolidMesh read_gmsh(const std::string& path);
};

}  // namespace lsmbs
