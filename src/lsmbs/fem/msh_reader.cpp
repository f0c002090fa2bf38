#include "lsmbs/fem/msh_reader.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <set>
#include <string_view>
#include <utility>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/file_check.hpp"
#include "lsmbs/core/text.hpp"

namespace lsmbs {

namespace {

constexpr long long kMaxCount = 100000000;  // counts above this are not a mesh lsmbs can hold

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
  // The first line of $Nodes or $Elements, "numBlocks numItems minTag maxTag" (item: "node" or
  // "element"): the numbers of blocks and items.
  std::pair<long long, long long> section_header(const std::string& item) const {
    const auto hd =
        fields(4, "the numbers of blocks and " + item + "s, the smallest and largest tag");
    const long long nblocks = integer(hd[0], "the number of " + item + " blocks", 0, kMaxCount);
    const long long n = integer(hd[1], "the number of " + item + "s", 0, kMaxCount);
    integer(hd[2], "the smallest " + item + " tag", 0);
    integer(hd[3], "the largest " + item + " tag", 0);
    return {nblocks, n};
  }
  // A block's header "entityDim entityTag third count" (third: what the block kind puts there),
  // its entity declared in $Entities when the file has one.
  struct Block {
    int edim;
    long long etag, third, count;
  };
  Block block_header(const std::string& item, const std::string& third, long long third_lo,
                     long long third_hi,
                     const std::set<std::pair<int, long long>>& entities) const {
    const std::string a = item == "element" ? "an " : "a ";
    const auto bh =
        fields(4, a + item + " block: entity dimension, entity tag, " + third + ", count");
    Block b{static_cast<int>(integer(bh[0], "the entity dimension", 0, 3)),
            integer(bh[1], "the entity tag", 1), integer(bh[2], third, third_lo, third_hi),
            integer(bh[3], "the number of " + item + "s in the block", 0, kMaxCount)};
    if (!entities.empty() && !entities.count({b.edim, b.etag}))
      fail("the " + item + " block's entity " + std::to_string(b.etag) + " of dimension " +
           std::to_string(b.edim) + " is not declared in $Entities");
    return b;
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

// Lower-dimensional elements that carry node sets (their physical groups).
struct SetCarrier {
  long long gmsh_type;
  int dim, nodes;
  const char* name;
};
constexpr SetCarrier kSetCarriers[] = {{15, 0, 1, "15 (points)"},
                                       {1, 1, 2, "1 (2-node lines)"},
                                       {2, 2, 3, "2 (3-node triangles)"},
                                       {3, 2, 4, "3 (4-node quadrangles)"}};
const SetCarrier* set_carrier(long long type) {
  for (const auto& c : kSetCarriers)
    if (c.gmsh_type == type) return &c;
  return nullptr;
}

}  // namespace

MshFile read_msh41(const std::string& path, int dim, const std::vector<MshCellType>& cell_types) {
  if (const auto why = unreadable_file_reason(path); !why.empty())
    throw Error(path, "", "mesh file: " + why);
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path, "", "cannot open mesh file");
  Reader rd{f, path, 0, {}};
  MshFile m;
  auto& node_tag = m.node_tag;  // per node index: its Gmsh tag and the line of its coordinates
  auto& node_line = m.node_line;
  std::map<long long, int> node_index;    // Gmsh tag -> node index
  std::map<long long, int> element_line;  // Gmsh element tag -> its line
  std::map<long long, std::string> phys_names[4];
  std::set<std::pair<int, long long>> entities;                // (dim, tag) declared in $Entities
  std::map<long long, std::vector<long long>> entity_phys[4];  // entity tag -> physical tags
  auto& sets = m.sets;
  std::set<std::string> seen;  // sections read
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
      const auto [nblocks, nnodes] = rd.section_header("node");
      m.nodes.reserve(static_cast<size_t>(std::min(nnodes, 10000000LL)));  // a claim, not data
      long long total = 0;
      for (long long b = 0; b < nblocks; ++b) {
        rd.next_in(s);
        const auto blk = rd.block_header("node", "parametric (0 or 1)", 0, 1, entities);
        const int edim = blk.edim;
        const bool parametric = blk.third == 1;
        const long long nb = blk.count;
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
          const auto [it, fresh] = node_index.emplace(tags[i], static_cast<int>(m.nodes.size()));
          if (!fresh)
            rd.fail("node tag " + std::to_string(tags[i]) + " is defined twice (first on line " +
                    std::to_string(node_line[static_cast<size_t>(it->second)]) + ")");
          m.nodes.emplace_back(x, y, z);
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
      const auto [nblocks, nelem] = rd.section_header("element");
      long long total = 0;
      for (long long b = 0; b < nblocks; ++b) {
        rd.next_in(s);
        const auto blk = rd.block_header("element", "the element type", 1,
                                         std::numeric_limits<long long>::max(), entities);
        const int edim = blk.edim;
        const long long etag = blk.etag, etype = blk.third, nb = blk.count;
        // points and lines (and in 3D triangles and quadrangles) carry node sets; cells are of
        // the types given
        int nn = 0, tdim = 0;
        const MshCellType* cell_kind = nullptr;
        for (const auto& t : cell_types)
          if (t.gmsh_type == etype) cell_kind = &t;
        if (cell_kind) {
          nn = cell_kind->nodes, tdim = dim;
        } else if (const auto* c = set_carrier(etype); c && c->dim < dim) {
          nn = c->nodes, tdim = c->dim;
        } else {
          std::string known;
          for (const auto& c : kSetCarriers)
            if (c.dim < dim) known += std::string(", ") + c.name;
          for (const auto& t : cell_types)
            known += ", " + std::to_string(t.gmsh_type) + " (" + t.name + ")";
          rd.fail("unsupported element type " + std::to_string(etype) + " (expected " +
                  known.substr(2) + ")");
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
          MshCell q{etype, std::vector<int>(static_cast<size_t>(nn)), tag, rd.line};
          for (int k = 0; k < nn; ++k) {
            const long long nt = rd.integer(el[static_cast<size_t>(1 + k)], "a node tag", 1);
            const auto it = node_index.find(nt);
            if (it == node_index.end())
              rd.fail("element " + std::to_string(tag) + " refers to unknown node " +
                      std::to_string(nt));
            q.nodes[static_cast<size_t>(k)] = it->second;
            for (int j = 0; j < k; ++j)
              if (tdim == dim && q.nodes[static_cast<size_t>(j)] == it->second)
                rd.fail(std::string(cell_kind->noun) + " " + std::to_string(tag) +
                        " repeats node " + std::to_string(nt) + " (its " + std::to_string(nn) +
                        " corners must be distinct)");
            if (tdim < dim)
              for (const auto& g : groups) sets[g].insert(it->second);
          }
          if (tdim == dim) m.cells.push_back(std::move(q));
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
  return m;
}

void MshFile::drop_unused_nodes() {
  std::vector<int> remap(nodes.size(), -1);
  for (const auto& c : cells)
    for (int k : c.nodes) remap[static_cast<size_t>(k)] = 0;
  std::vector<Vec3> kept;
  std::vector<long long> kept_tag;
  std::vector<int> kept_line;
  for (size_t i = 0; i < nodes.size(); ++i)
    if (remap[i] == 0) {
      remap[i] = static_cast<int>(kept.size());
      kept.push_back(nodes[i]);
      kept_tag.push_back(node_tag[i]);
      kept_line.push_back(node_line[i]);
    }
  nodes = std::move(kept);
  node_tag = std::move(kept_tag);
  node_line = std::move(kept_line);
  for (auto& c : cells)
    for (int& k : c.nodes) k = remap[static_cast<size_t>(k)];
  for (auto& [name, set] : sets) {
    std::set<int> kept_set;
    for (int k : set)
      if (remap[static_cast<size_t>(k)] >= 0) kept_set.insert(remap[static_cast<size_t>(k)]);
    set = std::move(kept_set);
  }
}

// Nodes closer than 1e-10 of the mesh size are found on a grid of that spacing (each node against
// the 3 × 3 × 3 cells around its own).
void MshFile::check_coincident_nodes(const std::string& path) const {
  std::vector<char> used(nodes.size(), 0);
  for (const auto& c : cells)
    for (int k : c.nodes) used[static_cast<size_t>(k)] = 1;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t i = 0; i < nodes.size(); ++i)
    if (used[i]) lo = lo.cwiseMin(nodes[i]), hi = hi.cwiseMax(nodes[i]);
  const double tol = 1e-10 * (hi - lo).norm();
  struct GridCell {
    std::array<long long, 3> i;
    int node;
    bool operator<(const GridCell& o) const { return i < o.i; }
  };
  std::vector<GridCell> grid;
  for (size_t i = 0; i < nodes.size(); ++i)
    if (used[i]) {
      const Vec3 r = tol > 0 ? Vec3((nodes[i] - lo) / tol) : Vec3::Zero();
      grid.push_back(
          {{static_cast<long long>(std::floor(r.x())), static_cast<long long>(std::floor(r.y())),
            static_cast<long long>(std::floor(r.z()))},
           static_cast<int>(i)});
    }
  std::sort(grid.begin(), grid.end());
  const bool planar = lo.z() == 0 && hi.z() == 0;
  for (const GridCell& c : grid)
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz) {
          const GridCell key{{c.i[0] + dx, c.i[1] + dy, c.i[2] + dz}, 0};
          const auto [b, e] = std::equal_range(grid.begin(), grid.end(), key);
          for (auto o = b; o != e; ++o) {
            if (o->node <= c.node) continue;
            const size_t i = static_cast<size_t>(c.node), j = static_cast<size_t>(o->node);
            if ((nodes[j] - nodes[i]).norm() > tol) continue;
            char where[128];
            if (planar)
              std::snprintf(where, sizeof where, "(%.17g, %.17g)", nodes[i].x(), nodes[i].y());
            else
              std::snprintf(where, sizeof where, "(%.17g, %.17g, %.17g)", nodes[i].x(),
                            nodes[i].y(), nodes[i].z());
            throw Error(path, "line " + std::to_string(node_line[j]),
                        "nodes " + std::to_string(node_tag[i]) + " (line " +
                            std::to_string(node_line[i]) + ") and " + std::to_string(node_tag[j]) +
                            " coincide at " + where +
                            ": the cells on either side are not connected there (make "
                            "the geometry coherent in Gmsh, or remove duplicate nodes)");
          }
        }
}

}  // namespace lsmbs
