// Mesh generation and the Gmsh v4 reader, against hand-computed geometry.
#include "lsmbs/fem/mesh.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/element_types.hpp"

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

// A sliver (area 5e-13 of its longest edge squared) would swamp the forces near it in round-off:
// refused by tag and line; a thin but sound triangle (1e-6) is read.
TEST(Mesh2D, GmshSliversAreRefusedAndThinCellsRead) {
  auto msh = [](const char* apex_y) {
    return std::string(
               "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n"
               "0 0 0\n1 0 0\n0.5 ") +
           apex_y + " 0\n$EndNodes\n$Elements\n1 1 1 1\n2 1 2 1\n7 1 2 3\n$EndElements\n";
  };
  EXPECT_EQ(Mesh2D::read_gmsh(write_temp("thin.msh", msh("2e-6"))).num_elements(), 1);
  try {
    Mesh2D::read_gmsh(write_temp("sliver.msh", msh("1e-12")));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("sliver.msh: line 17: triangle 7 is nearly flat: its area "
                                         "is 5e-13 times its longest edge squared"),
              std::string::npos)
        << e.what();
  }
}

TEST(Mesh2D, GmshTrianglesAreReadAndOtherCellTypesRejectedWithTheFileName) {
  const std::string msh =
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 "
      "0\n$EndNodes\n"
      "$Elements\n1 1 1 1\n2 1 2 1\n1 1 3 2\n$EndElements\n";
  // a clockwise triangle is read counter-clockwise: the right triangle of area 1/2
  const Mesh2D m = Mesh2D::read_gmsh(write_temp("tri.msh", msh));
  ASSERT_EQ(m.num_elements(), 1);
  EXPECT_EQ(element_type(m.cells[0].type).nodes, 3);
  EXPECT_DOUBLE_EQ(element_type(m.cells[0].type).shape->area(m.cell_nodes(0).data()), 0.5);
  // a 6-node triangle (Gmsh type 9) is not a registered type
  std::string six = msh;
  six.replace(six.find("2 1 2 1\n1 1 3 2\n"), 16, "2 1 9 1\n1 1 3 2 1 2 3\n");
  const std::string p = write_temp("tri6.msh", six);
  try {
    Mesh2D::read_gmsh(p);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("tri6.msh"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("unsupported element type 9"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("2 (tri3)"), std::string::npos) << e.what();
  }
}

namespace {

// The two-quad mesh of ReadsGmshV4QuadsAndPhysicalLines (lines numbered from 1).
const std::string kTwoQuads = R"($MeshFormat
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

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

// The message of Mesh2D::read_gmsh on `text` (empty when it reads).
std::string gmsh_error(const std::string& text) {
  const std::string p = write_temp("bad.msh", text);
  try {
    Mesh2D::read_gmsh(p);
  } catch (const Error& e) {
    return e.what();
  }
  return {};
}

}  // namespace

// Each of these was read without a word, and the mesh (and the results) changed: a quad with a
// repeated node, two coincident nodes (a crack), a node tag defined twice, a missing $EndNodes or
// $EndElements, an extra node tag on an element line, a number with a suffix; a bow-tie quad was
// refused by its index in the model, not its tag and line. Each is refused
// with the file, the line and what was expected.
TEST(Mesh2D, GmshReaderRefusesWhatItWouldMisread) {
  ASSERT_EQ(gmsh_error(kTwoQuads), "");
  // a third quad's node 8 at (1, 0), where node 2 is: quad 3 no longer shares node 2 with quad 2
  const std::string crack = replaced(
      replaced(
          replaced(replaced(kTwoQuads, "3 7 1 7\n", "4 8 1 8\n"), "3 2 3 6 5\n", "3 8 3 6 5\n"),
          "$EndNodes\n", "2 8 0 1\n8\n1 0 0\n$EndNodes\n"),
      "1 1 1 0\n", "1 1 2 0\n");
  const std::string crack_entities =
      replaced(crack, "1 0 0 0 2 1 0 1 2 0\n", "1 0 0 0 2 1 0 1 2 0\n8 0 0 0 2 1 0 0 0\n");
  struct Bad {
    std::string text, message;
  };
  const Bad bad[] = {
      {replaced(kTwoQuads, "3 2 3 6 5\n", "3 2 3 6 6\n"),
       "bad.msh: line 41: quadrilateral 3 repeats node 6 (its 4 corners must be distinct)"},
      {replaced(kTwoQuads, "3 2 3 6 5\n", "3 2 3 5 6\n"),
       "bad.msh: line 41: quadrilateral 3 is self-intersecting or degenerate (det J <= 0 at a "
       "Gauss point"},
      {crack_entities,
       "bad.msh: line 37: nodes 2 (line 31) and 8 coincide at (1, 0): the cells on "
       "either side are not connected there"},
      {replaced(kTwoQuads, "2\n3\n5\n6\n", "2\n2\n5\n6\n"),
       "bad.msh: line 31: node tag 2 is defined twice (first on line 30)"},
      {replaced(kTwoQuads, "$EndNodes\n", ""),
       "bad.msh: line 34: expected $EndNodes (the end of $Nodes, whose counts say its data ends "
       "here), got '$Elements'"},
      {replaced(kTwoQuads, "$EndElements\n", ""),
       "bad.msh: line 41: unexpected end of file: expected $EndElements (the end of $Elements)"},
      {replaced(kTwoQuads, "2 1 2 5 4\n", "2 1 2 5 4 7\n"),
       "bad.msh: line 40: expected an element: its tag and 4 node tags (5 fields), got 6 fields: "
       "'2 1 2 5 4 7'"},
      {replaced(kTwoQuads, "1 1 0\n2 1 0\n$EndNodes", "1x 1 0\n2 1 0\n$EndNodes"),
       "bad.msh: line 32: expected x (a finite number), got '1x'"},
      {replaced(kTwoQuads, "2 1 0 4\n", "2 1 0 5\n"),
       "bad.msh: line 25: more nodes than the 7 announced on line 16"},
      {replaced(kTwoQuads, "3 7 1 7\n", "3 8 1 7\n"),
       "bad.msh: line 33: the blocks hold 7 nodes, line 16 announces 8"},
      {replaced(kTwoQuads, "2 1 0\n", "2 1 0.5\n"),
       "bad.msh: line 33: node 6 has z = 0.5: lsmbs meshes are planar and lie in the plane z = 0"},
      {replaced(kTwoQuads, "2 1 3 2\n", "2 9 3 2\n"),
       "bad.msh: line 39: the element block's entity 9 of dimension 2 is not declared in "
       "$Entities"},
      {replaced(kTwoQuads, "2 1 3 2\n", "1 1 3 2\n"),
       "bad.msh: line 39: element type 3 has dimension 2, but the block's entity has dimension 1"},
      {replaced(kTwoQuads, "2 1 2 5 4\n", "2 1 2 5 9\n"),
       "bad.msh: line 40: element 2 refers to unknown node 9"},
      {replaced(kTwoQuads, "3 2 3 6 5\n", "2 2 3 6 5\n"),
       "bad.msh: line 41: element tag 2 is defined twice (first on line 40)"},
      {replaced(kTwoQuads, "4.1 0 8\n", "4.0 0 8\n"),
       "bad.msh: line 2: expected Gmsh format 4.1 (MSH 4.1 ASCII, Gmsh's default since version "
       "4.1), got 4.0"},
      {replaced(kTwoQuads, "$EndEntities\n", "$EndEntities\n$EndEntities\n"),
       "bad.msh: line 15: $EndEntities without its section"},
      {replaced(kTwoQuads, "7 5 5 0 0\n", "7 5 5 0 0 3\n"),
       "bad.msh: line 11: expected 5 fields on this entity line, got 6: '7 5 5 0 0 3'"},
      {replaced(kTwoQuads, "$EndPhysicalNames\n", "$EndPhysicalNames\n$Periodic\n0\n"),
       "bad.msh: line 9: the section '$Periodic' has no '$EndPeriodic' before the end of the file"},
  };
  for (const auto& b : bad) {
    const std::string msg = gmsh_error(b.text);
    EXPECT_NE(msg.find(testing::TempDir() + b.message), std::string::npos)
        << "message: " << msg << "\nexpected: " << b.message;
  }
  // an unknown section with its end marker is skipped: the same mesh
  const std::string periodic =
      replaced(kTwoQuads, "$EndPhysicalNames\n", "$EndPhysicalNames\n$Periodic\n0\n$EndPeriodic\n");
  EXPECT_EQ(gmsh_error(periodic), "");
  EXPECT_EQ(Mesh2D::read_gmsh(write_temp("periodic.msh", periodic)).num_elements(), 2);
}
