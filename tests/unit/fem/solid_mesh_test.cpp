// Gmsh meshes of solid bodies (fem/solid_mesh.hpp, msh_reader.hpp): the shipped meshes of
// data/spatial/meshes (written by Gmsh itself, make_meshes.py) against closed-form volumes and
// the box mesher's hexahedra, and small hand-written files for the reader's refusals.
#include "lsmbs/fem/solid_mesh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>
#include <string>

#include "lsmbs/core/error.hpp"

using namespace lsmbs;

namespace {

const std::string kMeshes = std::string(LSMBS_SOURCE_DIR) + "/data/spatial/meshes/";

double tet_volume(const SolidMesh& m, const std::vector<int>& c) {
  Mat3 J;
  for (int k = 0; k < 3; ++k)
    J.col(k) = m.nodes[static_cast<size_t>(c[static_cast<size_t>(k + 1)])] -
               m.nodes[static_cast<size_t>(c[0])];
  return J.determinant() / 6;
}

// A file with the given $Nodes and $Elements bodies (MSH 4.1, no $Entities).
std::string write_msh(const std::string& name, const std::string& nodes,
                      const std::string& elements) {
  const std::string path = testing::TempDir() + name;
  std::ofstream(path) << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n"
                      << nodes << "$EndNodes\n$Elements\n"
                      << elements << "$EndElements\n";
  return path;
}

std::string error_of(const std::string& path) {
  try {
    SolidMesh::read_gmsh(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

// the unit cube's eight corners as one node block
const char* kCubeNodes =
    "1 8 1 8\n3 1 0 8\n1\n2\n3\n4\n5\n6\n7\n8\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n";

}  // namespace

// Gmsh's tetrahedra of the unit cube: every one positively oriented, their volumes summing to 1,
// and the physical surfaces as node sets on their planes (the volume's group is no node set).
TEST(SolidMeshGmsh, TheUnitCubeInTetrahedra) {
  const SolidMesh m = SolidMesh::read_gmsh(kMeshes + "cube_tets.msh");
  ASSERT_GT(m.num_elements(), 100);
  double V = 0;
  for (const auto& c : m.cells) {
    ASSERT_EQ(c.size(), 4u);
    const double v = tet_volume(m, c);
    EXPECT_GT(v, 0);
    V += v;
  }
  EXPECT_NEAR(V, 1, 1e-12);
  ASSERT_TRUE(m.node_sets.count("bottom") && m.node_sets.count("top"));
  EXPECT_FALSE(m.node_sets.count("cube"));
  for (const auto& [name, z] : {std::pair<std::string, double>{"bottom", 0.0}, {"top", 1.0}}) {
    const auto& set = m.node_sets.at(name);
    EXPECT_GE(set.size(), 36u) << name;  // at least the 6 × 6 nodes of a 0.2 grid
    for (int n : set) EXPECT_NEAR(m.nodes[static_cast<size_t>(n)].z(), z, 1e-12) << name;
  }
  // every node is used by a tetrahedron (Gmsh's geometry points are mesh nodes here)
  std::set<int> used;
  for (const auto& c : m.cells) used.insert(c.begin(), c.end());
  EXPECT_EQ(used.size(), m.nodes.size());
}

// Gmsh's transfinite, recombined beam is the box mesher's 20 × 1 × 1 hexahedra: the same cells
// (as sets of corner positions, each with the same orientation: det J > 0 at the centre), and
// its physical surfaces "root" and "tip" the box's xmin and xmax.
TEST(SolidMeshGmsh, TheTransfiniteBeamIsTheBoxMesh) {
  const SolidMesh g = SolidMesh::read_gmsh(kMeshes + "beam_hex.msh");
  const SolidMesh b = SolidMesh::box(Vec3(0, -0.5, -0.5), Vec3(10, 1, 1), {20, 1, 1});
  ASSERT_EQ(g.num_elements(), b.num_elements());
  ASSERT_EQ(g.num_nodes(), b.num_nodes());
  const auto key = [](const SolidMesh& m, const std::vector<int>& c) {
    std::set<std::array<long long, 3>> k;
    for (int n : c) {
      const Vec3& x = m.nodes[static_cast<size_t>(n)];
      k.insert({std::llround(x.x() * 1e6), std::llround(x.y() * 1e6), std::llround(x.z() * 1e6)});
    }
    return k;
  };
  std::set<std::set<std::array<long long, 3>>> box_cells;
  for (const auto& c : b.cells) box_cells.insert(key(b, c));
  for (const auto& c : g.cells) {
    ASSERT_EQ(c.size(), 8u);
    EXPECT_TRUE(box_cells.count(key(g, c)));
    // the trilinear map's Jacobian at the centre: (x1 − x0, x3 − x0, x4 − x0) oriented as +x, +y,
    // +z
    const auto X = [&](int k) { return g.nodes[static_cast<size_t>(c[static_cast<size_t>(k)])]; };
    Mat3 J;
    J.col(0) = X(1) + X(2) + X(5) + X(6) - X(0) - X(3) - X(4) - X(7);
    J.col(1) = X(2) + X(3) + X(6) + X(7) - X(0) - X(1) - X(4) - X(5);
    J.col(2) = X(4) + X(5) + X(6) + X(7) - X(0) - X(1) - X(2) - X(3);
    EXPECT_GT(J.determinant(), 0);
  }
  for (const auto& [name, x] : {std::pair<std::string, double>{"root", 0.0}, {"tip", 10.0}}) {
    ASSERT_TRUE(g.node_sets.count(name)) << name;
    EXPECT_EQ(g.node_sets.at(name).size(), 4u) << name;
    for (int n : g.node_sets.at(name)) EXPECT_NEAR(g.nodes[static_cast<size_t>(n)].x(), x, 1e-9);
  }
}

// A tetrahedron listed inside out is reordered; a hexahedron whose corners are out of order
// (folded) is refused with its tag and line; a file of surface cells only, a second-order
// tetrahedron and coincident nodes are said so.
TEST(SolidMeshGmsh, RefusalsNameTheCellAndLine) {
  const SolidMesh t = SolidMesh::read_gmsh(
      write_msh("inside_out.msh", "1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n",
                "1 1 7 7\n3 1 4 1\n7 1 3 2 4\n"));
  EXPECT_NEAR(tet_volume(t, t.cells[0]), 1.0 / 6, 1e-15);
  const std::string folded =
      error_of(write_msh("folded.msh", kCubeNodes, "1 1 9 9\n3 1 5 1\n9 1 2 4 3 5 6 7 8\n"));
  EXPECT_NE(folded.find("line 27: hexahedron 9 is inverted in part, self-intersecting or "
                        "degenerate"),
            std::string::npos)
      << folded;
  const std::string flat =
      error_of(write_msh("flat.msh", kCubeNodes, "1 1 1 1\n2 1 3 1\n1 1 2 3 4\n"));
  EXPECT_NE(flat.find("the mesh contains no 3-D cells (4-node tetrahedra or 8-node hexahedra)"),
            std::string::npos)
      << flat;
  const std::string second =
      error_of(write_msh("tet10.msh", kCubeNodes, "1 1 1 1\n3 1 11 1\n1 1 2 3 4 5 6 7 8 1 2\n"));
  EXPECT_NE(second.find("unsupported element type 11 (expected 15 (points), 1 (2-node lines), "
                        "2 (3-node triangles), 3 (4-node quadrangles), 4 (tet4), 5 (hex8))"),
            std::string::npos)
      << second;
  const std::string twice = error_of(
      write_msh("twice.msh", "1 5 1 5\n3 1 0 5\n1\n2\n3\n4\n5\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0\n",
                "1 2 1 2\n3 1 4 2\n1 1 2 3 4\n2 5 3 4 1\n"));
  EXPECT_NE(twice.find("nodes 2 (line 13) and 5 coincide at (1, 0, 0)"), std::string::npos)
      << twice;
}
