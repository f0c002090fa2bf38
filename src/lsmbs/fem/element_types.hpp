#pragma once
// The registry of planar element types: one entry per type names everything the rest of the code
// needs of it (its cell shape, its Gmsh and VTK codes, its name in case files, and how to build
// its PlaneElement). Meshes, the level-set map, the pictures, the outputs and the flexible bodies
// go through it and know no element type by name. A new element type is its own file (a
// CellShape and a PlaneElement) and one entry in element_types.cpp; docs/extending.md has the
// recipe.
#include <memory>
#include <span>
#include <string_view>

#include "lsmbs/fem/cell.hpp"
#include "lsmbs/fem/plane_element.hpp"

namespace lsmbs {

struct ElementType {
  const char* name;  ///< in case files: a rectangle mesh's "cells", messages
  const char* noun;  ///< in messages: "quadrilateral 3 repeats node 6"
  int nodes;         ///< nodes of a cell
  int gmsh_type;     ///< Gmsh's element type number
  int vtk_type;      ///< VTK's cell type number
  const CellShape* shape;
  /// The element on the reference node positions X (counter-clockwise); throws lsmbs::Error for
  /// an inverted or degenerate element.
  std::unique_ptr<PlaneElement> (*make)(const Vec2* X, const ElementOptions& options);
};

/// Every registered type; CellType{i} is the i-th.
std::span<const ElementType> element_types();
const ElementType& element_type(CellType cell);
/// By case-file name or Gmsh number (the CellType through `cell`); null when none is registered.
const ElementType* element_type_named(std::string_view name, CellType* cell = nullptr);
const ElementType* element_type_for_gmsh(int gmsh_type, CellType* cell = nullptr);
/// The cell type registered under `name` (a type lsmbs itself uses: throws std::logic_error when
/// missing).
CellType cell_type(std::string_view name);
/// A cell of the type registered under `name` with the given nodes.
Cell make_cell(CellType type, std::initializer_list<int> nodes);

}  // namespace lsmbs
