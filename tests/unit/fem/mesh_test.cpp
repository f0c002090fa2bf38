// Mesh generation and the Gmsh v4 reader, against hand-computed geometry.
#include "lsmbs/fem/mesh.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "lsmbs/core/error.hpp"

using namespace lsmbs;

TEST(Mesh2D, RectangleHasTheExpectedNodesElementsAreaAndEdgeSets) {
  const Mesh2D m = Mesh2D::rectangle(0.2, -0.025, 0.6, 0.05, 120, 10);
  EXPECT_EQ(m.num_nodes(), 121 * 11);
  EXPECT_EQ(m.num_elements(), 1200);
  EXPECT_NEAR(m.area(), 0.03, 1e-15);
  EXPECT_EQ(m.node_sets.at("left").size(), 11u);
  for (int n : m.node_sets.at("right")) EXPECT_NEAR(m.nodes[n].x(), 0.8, 1e-15);
  EXPECT_EQ(m.nodes_on_line_x(0.2), m.node_sets.at("left"));
}

TEST(Mesh2D, CircleSelectorFindsNodesOnTheCircleOnly) {
  const Mesh2D m = Mesh2D::rectangle(-1, -1, 2, 2, 2, 2);
  // nodes at distance 1 from the origin: (±1, 0), (0, ±1)
  EXPECT_EQ(m.nodes_on_circle(Vec2(0, 0), 1.0).size(), 4u);
  EXPECT_TRUE(m.nodes_on_circle(Vec2(0, 0), 0.5).empty());
}

namespace {
std::string write_temp(const std::string& name, const std::string& text) {
  const std::string p = testing::TempDir() + name;
  std::ofstream(p) << text;
  return p;
}
}  // namespace

TEST(Mesh2D, ReadsGmshV4QuadsAndPhysicalLines) {
  // Two quads [0,2]x[0,1]; physical line "left" on x = 0; a geometry point node (tag 7)
  // used by no quad is dropped.
  const std::string msh = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
1 1 "left"
2 2 "plate"
$EndPhysicalNames
$Entities
1 1 1 0
7 5 5 0 0
1 0 0 0 0 1 0 1 1 2 1 -4
1 0 0 0 2 1 0 1 2 0
$EndEntities
$Nodes
3 7 1 7
0 7 0 1
7
5 5 0
1 1 0 2
1
4
0 0 0
0 1 0
2 1 0 4
2
3
5
6
1 0 0
2 0 0
1 1 0
2 1 0
$EndNodes
$Elements
2 3 1 3
1 1 1 1
1 1 4
2 1 3 2
2 1 2 5 4
3 2 3 6 5
$EndElements
)";
  const Mesh2D m = Mesh2D::read_gmsh(write_temp("two_quads.msh", msh));
  EXPECT_EQ(m.num_elements(), 2);
  EXPECT_EQ(m.num_nodes(), 6);  // node 7 dropped
  EXPECT_NEAR(m.area(), 2.0, 1e-14);
  ASSERT_TRUE(m.node_sets.count("left"));
  EXPECT_EQ(m.node_sets.at("left").size(), 2u);
  for (int n : m.node_sets.at("left")) EXPECT_EQ(m.nodes[n].x(), 0.0);
}

TEST(Mesh2D, GmshTrianglesAreRejectedWithTheFileName) {
  const std::string msh =
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 "
      "0\n$EndNodes\n"
      "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n";
  const std::string p = write_temp("tri.msh", msh);
  try {
    Mesh2D::read_gmsh(p);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("tri.msh"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("triangles are not supported"), std::string::npos);
  }
}
