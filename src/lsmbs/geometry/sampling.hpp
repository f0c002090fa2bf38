#pragma once
// Sampling a body's mesh on a regular grid (the judgement of a design's resolution and the
// length-scale constraints measure the level set there, finer than the mesh).
#include <vector>

#include "lsmbs/fem/mesh.hpp"

namespace lsmbs {

/// A grid of spacing s over the mesh's bounding box; a point is inside when an element covers it.
struct SampleGrid {
  Vec2 lo = Vec2::Zero();
  double s = 0;
  int nx = 0, ny = 0;
  std::vector<char> inside;
  Vec2 point(int i, int j) const { return lo + s * Vec2(i + 0.5, j + 0.5); }
  int index(int i, int j) const { return j * nx + i; }
  bool covers(const Vec2& x) const;
};

SampleGrid make_sample_grid(const Mesh2D& mesh, double spacing);
/// The median of √(element area) [m]: the element size of a (possibly graded) mesh.
double median_element_size(const Mesh2D& mesh);

}  // namespace lsmbs
