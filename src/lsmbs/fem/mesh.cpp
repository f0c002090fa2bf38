#include "lsmbs/fem/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string_view>
#include <utility>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/file_check.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/fem/element_types.hpp"
#include "lsmbs/fem/msh_reader.hpp"

namespace lsmbs {

namespace {
// A cell whose area is below this fraction of its longest edge squared is refused (aspect ratio
// about 1e9; Mesh2D::read_gmsh).
constexpr double kMinFlatness = 1e-9;
}  // namespace

Mesh2D Mesh2D::rectangle(double x0, double y0, double lx, double ly, int nx, int ny,
                         const std::string& cells) {
  if (nx < 1 || ny < 1 || !(lx > 0) || !(ly > 0))
    throw Error("Mesh2D::rectangle: expected positive sizes and element counts");
  CellType type;
  if (!element_type_named(cells, &type) || (cells != "quad4" && cells != "tri3"))
    throw Error("Mesh2D::rectangle: cells '" + cells + "': expected quad4 or tri3");
  Mesh2D m;
  m.nodes.reserve((nx + 1) * (ny + 1));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.nodes.emplace_back(x0 + lx * i / nx, y0 + ly * j / ny);
  auto id = [nx](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      if (cells == "quad4") {
        m.cells.push_back(
            make_cell(type, {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)}));
      } else {
        m.cells.push_back(make_cell(type, {id(i, j), id(i + 1, j), id(i + 1, j + 1)}));
        m.cells.push_back(make_cell(type, {id(i, j), id(i + 1, j + 1), id(i, j + 1)}));
      }
  for (int j = 0; j <= ny; ++j) {
    m.node_sets["left"].push_back(id(0, j));
    m.node_sets["right"].push_back(id(nx, j));
  }
  for (int i = 0; i <= nx; ++i) {
    m.node_sets["bottom"].push_back(id(i, 0));
    m.node_sets["top"].push_back(id(i, ny));
  }
  return m;
}

double Mesh2D::size() const {
  if (nodes.empty()) return 0;
  Vec2 lo = nodes[0], hi = nodes[0];
  for (const auto& p : nodes) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

double Mesh2D::area() const {
  double a = 0;
  for (int e = 0; e < num_elements(); ++e)
    a += element_type(cells[e].type).shape->area(cell_nodes(e).data());
  return a;
}

std::vector<std::vector<int>> Mesh2D::boundary_loops() const {
  std::map<std::pair<int, int>, int> count;  // undirected edge -> cells
  for (const Cell& c : cells)
    for (int k = 0; k < c.size(); ++k) {
      const int a = c[k], b = c[(k + 1) % c.size()];
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  std::map<int, int> next;  // boundary edges a -> b as their cell orders them
  for (const Cell& c : cells)
    for (int k = 0; k < c.size(); ++k) {
      const int a = c[k], b = c[(k + 1) % c.size()];
      if (count[{std::min(a, b), std::max(a, b)}] == 1) next[a] = b;
    }
  std::vector<std::vector<int>> loops;
  while (!next.empty()) {
    std::vector<int> loop;
    int a = next.begin()->first;
    while (next.count(a)) {
      loop.push_back(a);
      const int b = next[a];
      next.erase(a);
      a = b;
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

std::array<Vec2, Cell::kMaxNodes> Mesh2D::cell_nodes(int e) const {
  std::array<Vec2, Cell::kMaxNodes> X;
  const Cell& c = cells[static_cast<size_t>(e)];
  for (int k = 0; k < c.size(); ++k) X[static_cast<size_t>(k)] = nodes[static_cast<size_t>(c[k])];
  return X;
}

Vec2 Mesh2D::centroid(int e) const {
  // the mean of the nodes (a quadrilateral's: the sum times 0.25, as always computed)
  const Cell& c = cells[static_cast<size_t>(e)];
  Vec2 sum = Vec2::Zero();
  for (int k : c) sum += nodes[static_cast<size_t>(k)];
  return c.size() == 4 ? Vec2(0.25 * sum) : Vec2(sum / c.size());
}

static double default_tol(const Mesh2D& m, double tol) { return tol >= 0 ? tol : 1e-6 * m.size(); }

std::vector<int> Mesh2D::nodes_on_line_x(double x0, double tol) const {
  tol = default_tol(*this, tol);
  std::vector<int> r;
  for (int i = 0; i < num_nodes(); ++i)
    if (std::abs(nodes[i].x() - x0) <= tol) r.push_back(i);
  return r;
}
std::vector<int> Mesh2D::nodes_on_line_y(double y0, double tol) const {
  tol = default_tol(*this, tol);
  std::vector<int> r;
  for (int i = 0; i < num_nodes(); ++i)
    if (std::abs(nodes[i].y() - y0) <= tol) r.push_back(i);
  return r;
}
std::vector<int> Mesh2D::nodes_on_circle(const Vec2& c, double rad, double tol) const {
  tol = default_tol(*this, tol);
  std::vector<int> r;
  for (int i = 0; i < num_nodes(); ++i)
    if (std::abs((nodes[i] - c).norm() - rad) <= tol) r.push_back(i);
  return r;
}
std::vector<int> Mesh2D::nodes_in_box(const Vec2& lo, const Vec2& hi) const {
  std::vector<int> r;
  for (int i = 0; i < num_nodes(); ++i)
    if ((nodes[i].array() >= lo.array()).all() && (nodes[i].array() <= hi.array()).all())
      r.push_back(i);
  return r;
}
int Mesh2D::nearest_node(const Vec2& p) const {
  int best = -1;
  double d = std::numeric_limits<double>::infinity();
  for (int i = 0; i < num_nodes(); ++i)
    if ((nodes[i] - p).squaredNorm() < d) {
      d = (nodes[i] - p).squaredNorm();
      best = i;
    }
  return best;
}

// ---------------------------------------------------------------- Gmsh 4.1 ASCII files
// (fem/msh_reader.hpp): the 2-D cells of every registered element type, in the plane z = 0.
Mesh2D Mesh2D::read_gmsh(const std::string& path) {
  std::vector<MshCellType> types;
  for (const auto& t : element_types()) types.push_back({t.gmsh_type, t.nodes, t.name, t.noun});
  MshFile f = read_msh41(path, 2, types);
  if (f.cells.empty())
    throw Error(path, "", "the mesh contains no 2-D cells (quadrilaterals or triangles)");
  Mesh2D m;
  for (const Vec3& x : f.nodes) m.nodes.emplace_back(x.x(), x.y());
  // The mesh is read in the plane z = 0: a mesh drawn in another plane would be projected onto
  // it without a word (z within round-off of 0 is accepted).
  size_t zi = 0;
  for (size_t i = 0; i < f.nodes.size(); ++i)
    if (std::abs(f.nodes[i].z()) > std::abs(f.nodes[zi].z())) zi = i;
  if (!f.nodes.empty() && std::abs(f.nodes[zi].z()) > 1e-9 * m.size()) {
    char z[32];
    std::snprintf(z, sizeof z, "%.17g", f.nodes[zi].z());
    throw Error(path, "line " + std::to_string(f.node_line[zi]),
                "node " + std::to_string(f.node_tag[zi]) + " has z = " + z +
                    ": lsmbs meshes are planar and lie in the plane z = 0 (draw the part in the "
                    "xy-plane)");
  }
  // Two nodes at one place split the mesh there: the quadrilaterals on either side share no node
  // and come apart under load (a geometry that is not coherent in Gmsh).
  f.check_coincident_nodes(path);
  for (const MshCell& c : f.cells) {
    Cell q;
    element_type_for_gmsh(static_cast<int>(c.gmsh_type), &q.type);
    q.count = static_cast<std::uint8_t>(c.nodes.size());
    for (size_t k = 0; k < c.nodes.size(); ++k) q[static_cast<int>(k)] = c.nodes[k];
    m.cells.push_back(q);
  }
  for (int e = 0; e < m.num_elements(); ++e) {  // orient counter-clockwise
    Cell& q = m.cells[static_cast<size_t>(e)];
    const ElementType& type = element_type(q.type);
    if (type.shape->area(m.cell_nodes(e).data()) < 0)
      std::reverse(q.begin() + 1, q.end());  // quadrilateral: swaps corners 1 and 3
    // The element needs det J > 0 at its integration points. A cell whose corners are not in
    // order around it (a bow-tie quadrilateral) or that is degenerate fails here, named by its
    // tag and line rather than by its index in the model.
    const auto X = m.cell_nodes(e);
    const MshCell& c = f.cells[static_cast<size_t>(e)];
    if (!(type.shape->min_det_J(X.data()) > 0))
      throw Error(path, "line " + std::to_string(c.line),
                  std::string(type.noun) + " " + std::to_string(c.tag) +
                      " is self-intersecting or degenerate (det J <= 0 at a Gauss point: its "
                      "corners are not in order around it, or it is flat or folded); list "
                      "the corners in order around the element");
    // A sliver far below the round-off of its neighbours' stiffness: its stiffness (∝ its
    // aspect ratio) swamps every force near it, and no solver result there means anything.
    double longest = 0;
    for (int k = 0; k < type.nodes; ++k)
      longest = std::max(
          longest,
          (X[static_cast<size_t>((k + 1) % type.nodes)] - X[static_cast<size_t>(k)]).norm());
    const double flatness = type.shape->area(X.data()) / (longest * longest);
    if (flatness < kMinFlatness) {
      char fl[32];
      std::snprintf(fl, sizeof fl, "%.3g", flatness);
      throw Error(path, "line " + std::to_string(c.line),
                  std::string(type.noun) + " " + std::to_string(c.tag) +
                      " is nearly flat: its area is " + fl +
                      " times its longest edge squared (below 1e-9; a stiffness that swamps "
                      "every force near it in round-off); remove the sliver in Gmsh");
    }
    // the orientation kept for the renumbering below
    for (size_t k = 0; k < c.nodes.size(); ++k)
      f.cells[static_cast<size_t>(e)].nodes[k] = q[static_cast<int>(k)];
  }
  // Nodes used by no cell (geometry points such as a bore centre) would carry neither mass nor
  // stiffness: dropped, the node sets kept consistent.
  f.drop_unused_nodes();
  m.nodes.clear();
  for (const Vec3& x : f.nodes) m.nodes.emplace_back(x.x(), x.y());
  for (size_t e = 0; e < f.cells.size(); ++e)
    for (size_t k = 0; k < f.cells[e].nodes.size(); ++k)
      m.cells[e][static_cast<int>(k)] = f.cells[e].nodes[k];
  for (const auto& [name, set] : f.sets)
    if (!set.empty()) m.node_sets[name].assign(set.begin(), set.end());
  return m;
}

}  // namespace lsmbs
