#pragma once
// Gmsh MSH 4.1 ASCII reader shared by planar meshes (Mesh2D::read_gmsh) and solid ones
// (SolidMesh::read_gmsh): nodes, the cells of one dimension, and node sets from the physical
// groups of the elements of lower dimension (points, lines, and in 3D triangles and
// quadrangles). Every line is read whole and every field parsed whole (lsmbs/core/text.hpp): a
// field that is not a number, a line with a field too many or too few, a section without its end
// marker or a count that does not match the data is an error naming the file and line, because
// a reader that skips what it does not expect reads another mesh than the one written.
#include <map>
#include <set>
#include <string>
#include <vector>

#include "lsmbs/core/types.hpp"

namespace lsmbs {

/// A cell type the caller accepts: its Gmsh element type, node count and names for messages.
struct MshCellType {
  long long gmsh_type;
  int nodes;
  std::string name;  ///< e.g. "quad4", in the list of supported types
  std::string noun;  ///< e.g. "quadrilateral", in messages about one cell
};

struct MshCell {
  long long gmsh_type;
  std::vector<int> nodes;  ///< node indices (into MshFile::nodes)
  long long tag;
  int line;  ///< where the element is written
};

struct MshFile {
  std::vector<Vec3> nodes;
  std::vector<long long> node_tag;  ///< per node: its Gmsh tag
  std::vector<int> node_line;       ///< per node: the line of its coordinates
  std::vector<MshCell> cells;       ///< the elements of the cell types given
  /// Physical groups of the lower-dimensional elements: the nodes of their elements, by name
  /// ("physical_<tag>" for an unnamed group).
  std::map<std::string, std::set<int>> sets;
  /// Drops the nodes that no cell uses (geometry points such as a bore centre: neither mass nor
  /// stiffness), renumbering cells and sets.
  void drop_unused_nodes();
  /// Throws lsmbs::Error if two nodes used by cells lie within 1e-10 of the mesh size of each
  /// other: the cells on either side are not connected there.
  void check_coincident_nodes(const std::string& path) const;
};

/// Reads the file's cells of dimension `dim` (2 or 3), each of one of `cell_types`. lsmbs::Error
/// naming the file and line for anything it cannot read exactly.
MshFile read_msh41(const std::string& path, int dim, const std::vector<MshCellType>& cell_types);

}  // namespace lsmbs
