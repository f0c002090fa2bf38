#pragma once
// Cells of a planar mesh and what their shape means to the code that is not finite-element
// physics: the level-set map (sub-cell integration of the volume fraction μ_e, §2), the design
// picture (a cell's fill and the zero contour of the level set inside it) and the VTK output (the
// cell type). One CellShape per cell type, found through the element registry
// (fem/element_types.hpp), so that this code knows no cell type by name.
#include <algorithm>
#include <array>
#include <cstdint>
#include <initializer_list>
#include <utility>
#include <vector>

#include "lsmbs/core/types.hpp"

namespace lsmbs {

/// A cell type of planar meshes: its index in the element registry (fem/element_types.hpp), where
/// each type is registered once, with its name ("quad4", "tri3"), shape and element.
struct CellType {
  std::uint8_t index = 0;
  bool operator==(const CellType&) const = default;
};

/// A mesh cell: its type and its nodes, counter-clockwise (the first `count` of `nodes`).
struct Cell {
  static constexpr int kMaxNodes = 9;
  CellType type;
  std::uint8_t count = 0;
  std::array<int, kMaxNodes> nodes{};

  Cell() = default;
  Cell(CellType t, std::initializer_list<int> n)
      : type(t), count(static_cast<std::uint8_t>(n.size())) {
    std::copy(n.begin(), n.end(), nodes.begin());
  }
  int size() const { return count; }
  int operator[](int k) const { return nodes[static_cast<size_t>(k)]; }
  int& operator[](int k) { return nodes[static_cast<size_t>(k)]; }
  const int* begin() const { return nodes.data(); }
  const int* end() const { return nodes.data() + count; }
  int* begin() { return nodes.data(); }
  int* end() { return nodes.data() + count; }
};

/// A sample of a sub-cell quadrature: a point and its weight (area).
struct CellSample {
  Vec2 x;
  double w = 0;
};

/// The geometry of one cell type. X: the cell's node positions, in its node order.
class CellShape {
 public:
  virtual ~CellShape() = default;
  virtual int num_nodes() const = 0;
  /// The cell's area.
  virtual double area(const Vec2* X) const = 0;
  /// The smallest det J of the map from the parent cell over the element's integration points
  /// (≤ 0: the corners are not in order around the cell, or it is flat or folded).
  virtual double min_det_J(const Vec2* X) const = 0;
  /// n × n-like sub-cells (n sub-cells per edge), one midpoint sample each with its area as the
  /// weight: the volume fraction of a cut cell is Σ w H(φ(x)) / Σ w. Appended to `out`, in a fixed
  /// order (the order the sums are taken in).
  virtual void samples(const Vec2* X, int n, std::vector<CellSample>& out) const = 0;
  /// The segments of the zero contour of a field linear (or bilinear) along the cell's edges with
  /// the nodal values phi; appended to `out`.
  virtual void contour(const Vec2* X, const double* phi,
                       std::vector<std::pair<Vec2, Vec2>>& out) const = 0;
};

}  // namespace lsmbs
