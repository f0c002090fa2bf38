#pragma once
// Mesh2D — a planar mesh of 4-node quadrilaterals with named node sets: a structured
// rectangle generator, a Gmsh .msh v4 ASCII reader, and geometric node selectors
// ("nodes on the line x = x0", "nodes on a circle"). Nodes are reference (undeformed)
// positions; quads are stored counter-clockwise.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "lsmbs/core/types.hpp"

namespace lsmbs {

struct Mesh2D {
  std::vector<Vec2> nodes;
  std::vector<std::array<int, 4>> quads;
  std::map<std::string, std::vector<int>> node_sets;  ///< from physical groups or selectors

  int num_nodes() const { return static_cast<int>(nodes.size()); }
  int num_elements() const { return static_cast<int>(quads.size()); }

  /// nx × ny elements on [x0, x0+lx] × [y0, y0+ly]; node sets "left", "right", "bottom", "top".
  static Mesh2D rectangle(double x0, double y0, double lx, double ly, int nx, int ny);
  /// Gmsh 4.x ASCII; quads only (throws lsmbs::Error naming the file otherwise). Physical
  /// groups of dimension 0 and 1 become node sets named after the group.
  static Mesh2D read_gmsh(const std::string& path);

  /// Bounding-box diagonal (a length scale for tolerances).
  double size() const;
  double area() const;
  Vec2 centroid(int e) const;

  // Selectors (tolerance relative to the mesh size when tol < 0).
  std::vector<int> nodes_on_line_x(double x0, double tol = -1) const;
  std::vector<int> nodes_on_line_y(double y0, double tol = -1) const;
  std::vector<int> nodes_on_circle(const Vec2& c, double r, double tol = -1) const;
  std::vector<int> nodes_in_box(const Vec2& lo, const Vec2& hi) const;
  /// Node nearest to p.
  int nearest_node(const Vec2& p) const;
};

}  // namespace lsmbs
