#include "lsmbs/fem/element_types.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include "lsmbs/fem/quad_element.hpp"
#include "lsmbs/fem/tri_element.hpp"

namespace lsmbs {
namespace {

std::unique_ptr<PlaneElement> make_quad4(const Vec2* X, const ElementOptions& o) {
  return std::make_unique<QuadElement>(
      std::array<Vec2, 4>{X[0], X[1], X[2], X[3]},
      o.full_integration ? QuadIntegration::kFull : QuadIntegration::kSelectiveShear);
}

std::unique_ptr<PlaneElement> make_tri3(const Vec2* X, const ElementOptions&) {
  return std::make_unique<TriElement>(std::array<Vec2, 3>{X[0], X[1], X[2]});
}

const QuadShape kQuadShape;
const TriShape kTriShape;

// The registry: a new element type is one line here (and its own file)
const ElementType kTypes[] = {
    {"quad4", "quadrilateral", 4, 3, 9, &kQuadShape, &make_quad4},
    {"tri3", "triangle", 3, 2, 5, &kTriShape, &make_tri3},
};

CellType type_at(size_t i) { return CellType{static_cast<std::uint8_t>(i)}; }

}  // namespace

std::span<const ElementType> element_types() { return kTypes; }

const ElementType& element_type(CellType cell) {
  if (cell.index >= std::size(kTypes))
    throw std::logic_error("element_type: unregistered cell type");
  return kTypes[cell.index];
}

const ElementType* element_type_named(std::string_view name, CellType* cell) {
  for (size_t i = 0; i < std::size(kTypes); ++i)
    if (name == kTypes[i].name) {
      if (cell) *cell = type_at(i);
      return &kTypes[i];
    }
  return nullptr;
}

const ElementType* element_type_for_gmsh(int gmsh_type, CellType* cell) {
  for (size_t i = 0; i < std::size(kTypes); ++i)
    if (kTypes[i].gmsh_type == gmsh_type) {
      if (cell) *cell = type_at(i);
      return &kTypes[i];
    }
  return nullptr;
}

CellType cell_type(std::string_view name) {
  CellType c;
  if (!element_type_named(name, &c))
    throw std::logic_error("cell_type: '" + std::string(name) + "' is not registered");
  return c;
}

Cell make_cell(CellType type, std::initializer_list<int> nodes) {
  if (static_cast<int>(nodes.size()) != element_type(type).nodes)
    throw std::logic_error("make_cell: wrong number of nodes");
  return Cell(type, nodes);
}

}  // namespace lsmbs
