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

// ---------------------------------------------------------------- Gmsh 4.1 ASCII reader
// Every line is read whole and every field parsed whole (lsmbs/core/text.hpp): a field that is
// not a number, a line with a field too many or too few, a section without its end marker or a
// count that does not match the data is an error naming the file and line, because a reader that
// skips what it does not expect reads another mesh than the one written.
namespace {

struct Reader {
  std::istream& in;
  const std::string& file;
  int line = 0;
  std::string text;  // the current line, without its line break

  bool next() {
    if (!std::getline(in, text)) return false;
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    return true;
  }
  // The current line as a section marker ($Nodes), without trailing blanks.
  std::string marker() const {
    const auto e = text.find_last_not_of(" \t");
    return e == std::string::npos ? std::string() : text.substr(0, e + 1);
  }
  // The next line of a section, whose end marker has not come yet.
  void next_in(const std::string& section) {
    if (!next())
      throw Error(file, "line " + std::to_string(line),
                  "unexpected end of file in the " + section +
                      " section (expected its data, then $End" + section.substr(1) + ")");
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(file, "line " + std::to_string(line), what);
  }
  // The fields of the current line: exactly n of them.
  std::vector<std::string_view> fields(size_t n, const std::string& what) const {
    auto f = whitespace_fields(text);
    if (f.size() != n)
      fail("expected " + what + " (" + std::to_string(n) + " fields), got " +
           std::to_string(f.size()) + " fields: " + shown(text));
    return f;
  }
  long long integer(std::string_view field, const std::string& what, long long lo,
                    long long hi = std::numeric_limits<long long>::max()) const {
    const auto v = parse_integer(field);
    if (!v) fail("expected " + what + " (an integer), got " + shown(field));
    if (*v < lo || *v > hi)
      fail("expected " + what + " in [" + std::to_string(lo) + ", " +
           (hi == std::numeric_limits<long long>::max() ? std::string("...") : std::to_string(hi)) +
           "], got " + std::string(field));
    return *v;
  }
  double real(std::string_view field, const std::string& what) const {
    const auto v = parse_finite_double(field);
    if (!v) fail("expected " + what + " (a finite number), got " + shown(field));
    return *v;
  }
  // The end marker of a section on the next line.
  void end(const std::string& section) {
    const std::string marker = "$End" + section.substr(1);
    if (!next())
      fail("unexpected end of file: expected " + marker + " (the end of " + section + ")");
    if (this->marker() != marker)
      fail("expected " + marker + " (the end of " + section +
           ", whose counts say its data ends here), got " + shown(text));
  }
};

constexpr long long kMaxCount = 100000000;  // counts above this are not a mesh lsmbs can hold

}  // namespace

Mesh2D Mesh2D::read_gmsh(const std::string& path) {
  if (const auto why = unreadable_file_reason(path); !why.empty())
    throw Error(path, "", "mesh file: " + why);
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path, "", "cannot open mesh file");
  Reader rd{f, path, 0, {}};
  Mesh2D m;
  std::vector<long long> node_tag;  // per node index: its Gmsh tag and the line of its coordinates
  std::vector<int> node_line;
  std::map<long long, int> node_index;    // Gmsh tag -> node index
  std::map<long long, int> element_line;  // Gmsh element tag -> its line
  std::vector<long long> cell_tag;        // per 2-D cell: its Gmsh element tag
  std::map<long long, std::string> phys_names[4];
  std::set<std::pair<int, long long>> entities;                // (dim, tag) declared in $Entities
  std::map<long long, std::vector<long long>> entity_phys[4];  // entity tag -> physical tags
  std::map<std::string, std::set<int>> sets;
  std::set<std::string> seen;  // sections read
  double max_z = 0;            // the largest |z| of a node, its line and tag
  int max_z_line = 0;
  long long max_z_tag = 0;
  bool first = true;
  while (rd.next()) {
    if (whitespace_fields(rd.text).empty()) continue;  // blank lines between sections
    const std::string s = rd.marker();
    if (s.empty() || s[0] != '$')
      rd.fail("expected a section ($MeshFormat, $Nodes, $Elements, ...), got " + shown(s));
    if (first && s != "$MeshFormat")
      rd.fail("not a Gmsh .msh file: it does not start with $MeshFormat (got " + shown(s) + ")");
    first = false;
    if (s.rfind("$End", 0) == 0) rd.fail(s + " without its section");
    if (!seen.insert(s).second && (s == "$MeshFormat" || s == "$PhysicalNames" ||
                                   s == "$Entities" || s == "$Nodes" || s == "$Elements"))
      rd.fail("a second " + s + " section");
    if (s == "$MeshFormat") {
      rd.next_in(s);
      const auto fl = rd.fields(3, "version, file type and data size");
      const double version = rd.real(fl[0], "the format version");
      if (version != 4.1)
        rd.fail("expected Gmsh format 4.1 (MSH 4.1 ASCII, Gmsh's default since version 4.1), got " +
                std::string(fl[0]));
      if (rd.integer(fl[1], "the file type (0: ASCII)", 0, 1) != 0)
        rd.fail("expected an ASCII .msh file (binary given)");
      rd.integer(fl[2], "the data size", 1);
      rd.end(s);
    } else if (s == "$PhysicalNames") {
      if (seen.count("$Elements")) rd.fail("$PhysicalNames after $Elements");
      rd.next_in(s);
      const long long n = rd.integer(rd.fields(1, "the number of physical names")[0],
                                     "the number of physical names", 0, kMaxCount);
      for (long long i = 0; i < n; ++i) {
        rd.next_in(s);
        // dim tag "name": the name is quoted and may hold spaces
        const auto q1 = rd.text.find('"'), q2 = rd.text.rfind('"');
        if (q1 == std::string::npos || q2 == q1 ||
            !whitespace_fields(std::string_view(rd.text).substr(q2 + 1)).empty())
          rd.fail("expected a physical name: dimension, tag and \"name\", got " + shown(rd.text));
        const std::string head = rd.text.substr(0, q1);
        const auto fl = whitespace_fields(head);
        if (fl.size() != 2)
          rd.fail("expected a physical name: dimension, tag and \"name\", got " + shown(rd.text));
        const int dim = static_cast<int>(rd.integer(fl[0], "the physical group's dimension", 0, 3));
        const long long tag = rd.integer(fl[1], "the physical group's tag", 1);
        const std::string name = rd.text.substr(q1 + 1, q2 - q1 - 1);
        if (invalid_utf8_at(name) != std::string::npos)
          rd.fail("the physical name " + shown(name) + " is not valid UTF-8");
        if (!phys_names[dim].emplace(tag, name).second)
          rd.fail("physical group " + std::to_string(tag) + " of dimension " + std::to_string(dim) +
                  " is named twice");
      }
      rd.end(s);
    } else if (s == "$PartitionedEntities") {
      rd.fail("partitioned meshes are not supported (save the mesh without partitions)");
    } else if (s == "$Entities") {
      if (seen.count("$Nodes") || seen.count("$Elements")) rd.fail("$Entities after $Nodes");
      rd.next_in(s);
      const auto hd = rd.fields(4, "the numbers of points, curves, surfaces and volumes");
      long long counts[4];
      for (int d = 0; d < 4; ++d)
        counts[d] = rd.integer(hd[static_cast<size_t>(d)], "an entity count", 0, kMaxCount);
      for (int dim = 0; dim < 4; ++dim)
        for (long long i = 0; i < counts[dim]; ++i) {
          rd.next_in(s);
          // point: tag x y z nphys phys…; curve, surface, volume: tag box(6) nphys phys…
          // nbound bound…
          const auto fl = whitespace_fields(rd.text);
          const size_t nbox = dim == 0 ? 3 : 6;
          size_t k = 0;
          auto field = [&](const std::string& what) {
            if (k >= fl.size())
              rd.fail("expected " + what +
                      " on this entity line (too few fields): " + shown(rd.text));
            return fl[k++];
          };
          const long long tag = rd.integer(field("the entity tag"), "the entity tag", 1);
          for (size_t b = 0; b < nbox; ++b) rd.real(field("a coordinate"), "a coordinate");
          const long long nphys = rd.integer(field("the number of physical tags"),
                                             "the number of physical tags", 0, kMaxCount);
          auto& phys = entity_phys[dim][tag];
          for (long long p = 0; p < nphys; ++p) {
            const long long t = rd.integer(field("a physical tag"), "a physical tag",
                                           -std::numeric_limits<long long>::max());
            if (t == 0) rd.fail("expected a non-zero physical tag, got 0");
            phys.push_back(std::abs(t));
          }
          if (dim > 0) {
            const long long nb = rd.integer(field("the number of bounding entities"),
                                            "the number of bounding entities", 0, kMaxCount);
            for (long long b = 0; b < nb; ++b)
              rd.integer(field("a bounding entity tag"), "a bounding entity tag",
                         -std::numeric_limits<long long>::max());
          }
          if (k != fl.size())
            rd.fail("expected " + std::to_string(k) + " fields on this entity line, got " +
                    std::to_string(fl.size()) + ": " + shown(rd.text));
          if (!entities.emplace(dim, tag).second)
            rd.fail("entity " + std::to_string(tag) + " of dimension " + std::to_string(dim) +
                    " is declared twice");
        }
      rd.end(s);
    } else if (s == "$Nodes") {
      rd.next_in(s);
      const int header = rd.line;
      const auto hd = rd.fields(4, "the numbers of blocks and nodes, the smallest and largest tag");
      const long long nblocks = rd.integer(hd[0], "the number of node blocks", 0, kMaxCount);
      const long long nnodes = rd.integer(hd[1], "the number of nodes", 0, kMaxCount);
      rd.integer(hd[2], "the smallest node tag", 0);
      rd.integer(hd[3], "the largest node tag", 0);
      m.nodes.reserve(static_cast<size_t>(std::min(nnodes, 10000000LL)));  // a claim, not data
      long long total = 0;
      for (long long b = 0; b < nblocks; ++b) {
        rd.next_in(s);
        const auto bh =
            rd.fields(4, "a node block: entity dimension, entity tag, parametric, count");
        const int edim = static_cast<int>(rd.integer(bh[0], "the entity dimension", 0, 3));
        const long long etag = rd.integer(bh[1], "the entity tag", 1);
        const bool parametric = rd.integer(bh[2], "parametric (0 or 1)", 0, 1) == 1;
        const long long nb = rd.integer(bh[3], "the number of nodes in the block", 0, kMaxCount);
        if (!entities.empty() && !entities.count({edim, etag}))
          rd.fail("the node block's entity " + std::to_string(etag) + " of dimension " +
                  std::to_string(edim) + " is not declared in $Entities");
        total += nb;
        if (total > nnodes)
          rd.fail("more nodes than the " + std::to_string(nnodes) + " announced on line " +
                  std::to_string(header));
        std::vector<long long> tags;
        for (long long i = 0; i < nb; ++i) {
          rd.next_in(s);
          const long long tag = rd.integer(rd.fields(1, "a node tag")[0], "a node tag", 1);
          tags.push_back(tag);
        }
        const size_t ncoord = 3 + (parametric ? static_cast<size_t>(edim) : 0);
        for (long long i = 0; i < nb; ++i) {
          rd.next_in(s);
          const auto cl = rd.fields(ncoord, parametric ? "x, y, z and the parametric coordinates"
                                                       : "the coordinates x, y, z");
          const double x = rd.real(cl[0], "x"), y = rd.real(cl[1], "y"), z = rd.real(cl[2], "z");
          for (size_t k = 3; k < ncoord; ++k) rd.real(cl[k], "a parametric coordinate");
          if (std::abs(z) > std::abs(max_z)) {
            max_z = z;
            max_z_line = rd.line;
            max_z_tag = tags[i];
          }
          const auto [it, fresh] = node_index.emplace(tags[i], static_cast<int>(m.nodes.size()));
          if (!fresh)
            rd.fail("node tag " + std::to_string(tags[i]) + " is defined twice (first on line " +
                    std::to_string(node_line[static_cast<size_t>(it->second)]) + ")");
          m.nodes.emplace_back(x, y);
          node_tag.push_back(tags[i]);
          node_line.push_back(rd.line);
        }
      }
      if (total != nnodes)
        rd.fail("the blocks hold " + std::to_string(total) + " nodes, line " +
                std::to_string(header) + " announces " + std::to_string(nnodes));
      rd.end(s);
    } else if (s == "$Elements") {
      if (!seen.count("$Nodes")) rd.fail("$Elements before $Nodes");
      rd.next_in(s);
      const int header = rd.line;
      const auto hd =
          rd.fields(4, "the numbers of blocks and elements, the smallest and largest tag");
      const long long nblocks = rd.integer(hd[0], "the number of element blocks", 0, kMaxCount);
      const long long nelem = rd.integer(hd[1], "the number of elements", 0, kMaxCount);
      rd.integer(hd[2], "the smallest element tag", 0);
      rd.integer(hd[3], "the largest element tag", 0);
      long long total = 0;
      for (long long b = 0; b < nblocks; ++b) {
        rd.next_in(s);
        const auto bh =
            rd.fields(4, "an element block: entity dimension, entity tag, element type, count");
        const int edim = static_cast<int>(rd.integer(bh[0], "the entity dimension", 0, 3));
        const long long etag = rd.integer(bh[1], "the entity tag", 1);
        const long long etype = rd.integer(bh[2], "the element type", 1);
        const long long nb = rd.integer(bh[3], "the number of elements in the block", 0, kMaxCount);
        // points and 2-node lines carry node sets; 2-D cells of every registered type
        int nn = 0, tdim = 0;
        CellType cell_type;
        const ElementType* cell_kind = element_type_for_gmsh(static_cast<int>(etype), &cell_type);
        if (etype == 15) {
          nn = 1, tdim = 0;
        } else if (etype == 1) {
          nn = 2, tdim = 1;
        } else if (cell_kind) {
          nn = cell_kind->nodes, tdim = 2;
        } else {
          std::string known;
          for (const auto& t : element_types())
            known += std::string(", ") + std::to_string(t.gmsh_type) + " (" + t.name + ")";
          rd.fail("unsupported element type " + std::to_string(etype) +
                  " (expected 15 (points), 1 (2-node lines)" + known + ")");
        }
        if (edim != tdim)
          rd.fail("element type " + std::to_string(etype) + " has dimension " +
                  std::to_string(tdim) + ", but the block's entity has dimension " +
                  std::to_string(edim));
        if (!entities.empty() && !entities.count({edim, etag}))
          rd.fail("the element block's entity " + std::to_string(etag) + " of dimension " +
                  std::to_string(edim) + " is not declared in $Entities");
        total += nb;
        if (total > nelem)
          rd.fail("more elements than the " + std::to_string(nelem) + " announced on line " +
                  std::to_string(header));
        std::vector<std::string> groups;
        if (auto ep = entity_phys[edim].find(etag); ep != entity_phys[edim].end())
          for (long long p : ep->second) {
            const auto pn = phys_names[edim].find(p);
            groups.push_back(pn != phys_names[edim].end() ? pn->second
                                                          : "physical_" + std::to_string(p));
          }
        const std::string what = "an element: its tag and " + std::to_string(nn) +
                                 (nn == 1 ? " node tag" : " node tags");
        for (long long i = 0; i < nb; ++i) {
          rd.next_in(s);
          const auto el = rd.fields(static_cast<size_t>(1 + nn), what);
          const long long tag = rd.integer(el[0], "the element tag", 1);
          if (const auto [it, fresh] = element_line.emplace(tag, rd.line); !fresh)
            rd.fail("element tag " + std::to_string(tag) + " is defined twice (first on line " +
                    std::to_string(it->second) + ")");
          Cell q;
          q.type = cell_type;
          q.count = static_cast<std::uint8_t>(nn);
          for (int k = 0; k < nn; ++k) {
            const long long nt = rd.integer(el[static_cast<size_t>(1 + k)], "a node tag", 1);
            const auto it = node_index.find(nt);
            if (it == node_index.end())
              rd.fail("element " + std::to_string(tag) + " refers to unknown node " +
                      std::to_string(nt));
            q[k] = it->second;
            for (int j = 0; j < k; ++j)
              if (tdim == 2 && q[j] == it->second)
                rd.fail(std::string(cell_kind->noun) + " " + std::to_string(tag) +
                        " repeats node " + std::to_string(nt) + " (its " + std::to_string(nn) +
                        " corners must be distinct)");
            if (tdim < 2)
              for (const auto& g : groups) sets[g].insert(it->second);
          }
          if (tdim == 2) {
            m.cells.push_back(q);
            cell_tag.push_back(tag);
          }
        }
      }
      if (total != nelem)
        rd.fail("the blocks hold " + std::to_string(total) + " elements, line " +
                std::to_string(header) + " announces " + std::to_string(nelem));
      rd.end(s);
    } else {  // another section (Gmsh's $Periodic, $NodeData, …): skipped up to its end
      const int at = rd.line;
      const std::string marker = "$End" + s.substr(1);
      bool ended = false;
      while (!ended && rd.next()) ended = rd.marker() == marker;
      if (!ended)
        throw Error(
            path, "line " + std::to_string(at),
            "the section " + shown(s) + " has no " + shown(marker) + " before the end of the file");
    }
  }
  if (first) throw Error(path, "", "not a Gmsh .msh file ($MeshFormat missing)");
  if (m.cells.empty())
    throw Error(path, "", "the mesh contains no 2-D cells (quadrilaterals or triangles)");
  // The mesh is read in the plane z = 0: a mesh drawn in another plane would be projected onto
  // it without a word (z within round-off of 0 is accepted).
  if (std::abs(max_z) > 1e-9 * m.size()) {
    char z[32];
    std::snprintf(z, sizeof z, "%.17g", max_z);
    throw Error(path, "line " + std::to_string(max_z_line),
                "node " + std::to_string(max_z_tag) + " has z = " + z +
                    ": lsmbs meshes are planar and lie in the plane z = 0 (draw the part in the "
                    "xy-plane)");
  }
  // Two nodes at one place split the mesh there: the quadrilaterals on either side share no node
  // and come apart under load (a geometry that is not coherent in Gmsh). Nodes closer than
  // 1e-10 of the mesh size are found on a grid of that spacing (each node against the 3 × 3 cells
  // around its own).
  {
    std::vector<char> used(m.nodes.size(), 0);
    for (const auto& q : m.cells)
      for (int k : q) used[static_cast<size_t>(k)] = 1;
    Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (size_t i = 0; i < m.nodes.size(); ++i)
      if (used[i]) {
        lo = lo.cwiseMin(m.nodes[i]);
        hi = hi.cwiseMax(m.nodes[i]);
      }
    const double tol = 1e-10 * (hi - lo).norm();
    struct GridCell {
      long long ix, iy;
      int node;
      bool operator<(const GridCell& o) const { return ix != o.ix ? ix < o.ix : iy < o.iy; }
    };
    std::vector<GridCell> grid;
    for (size_t i = 0; i < m.nodes.size(); ++i)
      if (used[i]) {
        const Vec2 r = tol > 0 ? Vec2((m.nodes[i] - lo) / tol) : Vec2::Zero();
        grid.push_back({static_cast<long long>(std::floor(r.x())),
                        static_cast<long long>(std::floor(r.y())), static_cast<int>(i)});
      }
    std::sort(grid.begin(), grid.end());
    for (const GridCell& c : grid)
      for (long long dx = -1; dx <= 1; ++dx)
        for (long long dy = -1; dy <= 1; ++dy) {
          const auto [b, e] =
              std::equal_range(grid.begin(), grid.end(), GridCell{c.ix + dx, c.iy + dy, 0});
          for (auto o = b; o != e; ++o) {
            if (o->node <= c.node) continue;
            if ((m.nodes[static_cast<size_t>(o->node)] - m.nodes[static_cast<size_t>(c.node)])
                    .norm() > tol)
              continue;
            const size_t i = static_cast<size_t>(c.node), j = static_cast<size_t>(o->node);
            char where[96];
            std::snprintf(where, sizeof where, "(%.17g, %.17g)", m.nodes[i].x(), m.nodes[i].y());
            throw Error(path, "line " + std::to_string(node_line[j]),
                        "nodes " + std::to_string(node_tag[i]) + " (line " +
                            std::to_string(node_line[i]) + ") and " + std::to_string(node_tag[j]) +
                            " coincide at " + where +
                            ": the cells on either side are not connected there (make "
                            "the geometry coherent in Gmsh, or remove duplicate nodes)");
          }
        }
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
    const long long tag = cell_tag[static_cast<size_t>(e)];
    if (!(type.shape->min_det_J(X.data()) > 0))
      throw Error(path, "line " + std::to_string(element_line.at(tag)),
                  std::string(type.noun) + " " + std::to_string(tag) +
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
      char f[32];
      std::snprintf(f, sizeof f, "%.3g", flatness);
      throw Error(path, "line " + std::to_string(element_line.at(tag)),
                  std::string(type.noun) + " " + std::to_string(tag) +
                      " is nearly flat: its area is " + f +
                      " times its longest edge squared (below 1e-9; a stiffness that swamps "
                      "every force near it in round-off); remove the sliver in Gmsh");
    }
  }
  // Nodes used by no quad (geometry points such as a bore centre) would carry neither mass
  // nor stiffness: drop them and renumber, keeping node sets consistent.
  std::vector<int> remap(m.nodes.size(), -1);
  for (const auto& q : m.cells)
    for (int k : q) remap[k] = 0;
  std::vector<Vec2> kept;
  for (size_t i = 0; i < m.nodes.size(); ++i)
    if (remap[i] == 0) {
      remap[i] = static_cast<int>(kept.size());
      kept.push_back(m.nodes[i]);
    }
  m.nodes = std::move(kept);
  for (auto& q : m.cells)
    for (int& k : q) k = remap[k];
  for (auto& [name, s2] : sets)
    for (int k : s2)
      if (remap[k] >= 0) m.node_sets[name].push_back(remap[k]);
  return m;
}

}  // namespace lsmbs
