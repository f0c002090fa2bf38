#pragma once
// Mesh2D — a planar mesh of cells of any registered element type (fem/element_types.hpp: 4-node
// quadrilaterals, 3-node triangles) with named node sets: a structured rectangle generator, a
// Gmsh .msh v4 ASCII reader, and geometric node selectors ("nodes on the line x = x0", "nodes on
// a circle"). Nodes are reference (undeformed) positions; cells are stored counter-clockwise.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "lsmbs/core/types.hpp"
#include "lsmbs/fem/cell.hpp"

namespace lsmbs {

struct Mesh2D {
  std::vector<Vec2> nodes;
  std::vector<Cell> cells;
  std::map<std::string, std::vector<int>> node_sets;  ///< from physical groups or selectors

  int num_nodes() const { return static_cast<int>(nodes.size()); }
  int num_elements() const { return static_cast<int>(cells.size()); }

  /// nx × ny quadrilaterals on [x0, x0+lx] × [y0, y0+ly] (`cells` "quad4"), or each split into two
  /// triangles along its diagonal from the lower left ("tri3"); node sets "left", "right",
  /// "bottom", "top".
  static Mesh2D rectangle(double x0, double y0, double lx, double ly, int nx, int ny,
                          const std::string& cells = "quad4");
  /// Gmsh 4.x ASCII: cells of every registered 2-D type (throws lsmbs::Error naming the file and
  /// line otherwise). Physical groups of dimension 0 and 1 become node sets named after the group.
  static Mesh2D read_gmsh(const std::string& path);
  /// The node positions of cell e, in its order (at most Cell::kMaxNodes).
  std::array<Vec2, Cell::kMaxNodes> cell_nodes(int e) const;

  /// Bounding-box diagonal (a length scale for tolerances).
  double size() const;
  double area() const;
  Vec2 centroid(int e) const;
  /// The closed loops of the mesh's boundary (cell edges of one cell only), as node indices in
  /// the cells' order: the outer boundary counter-clockwise, holes clockwise. Corner nodes only
  /// (a cell's nodes taken in order around it).
  std::vector<std::vector<int>> boundary_loops() const;

  // Selectors (tolerance relative to the mesh size when tol < 0).
  std::vector<int> nodes_on_line_x(double x0, double tol = -1) const;
  std::vector<int> nodes_on_line_y(double y0, double tol = -1) const;
  std::vector<int> nodes_on_circle(const Vec2& c, double r, double tol = -1) const;
  std::vector<int> nodes_in_box(const Vec2& lo, const Vec2& hi) const;
  /// Node nearest to p.
  int nearest_node(const Vec2& p) const;
};

}  // namespace lsmbs
