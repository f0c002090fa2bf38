#include "lsmbs/fem/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/file_check.hpp"

namespace lsmbs {

Mesh2D Mesh2D::rectangle(double x0, double y0, double lx, double ly, int nx, int ny) {
  if (nx < 1 || ny < 1 || !(lx > 0) || !(ly > 0))
    throw Error("Mesh2D::rectangle: expected positive sizes and element counts");
  Mesh2D m;
  m.nodes.reserve((nx + 1) * (ny + 1));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.nodes.emplace_back(x0 + lx * i / nx, y0 + ly * j / ny);
  auto id = [nx](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      m.quads.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
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
  for (const auto& q : quads) {
    const Vec2 d1 = nodes[q[2]] - nodes[q[0]], d2 = nodes[q[3]] - nodes[q[1]];
    a += 0.5 * (d1.x() * d2.y() - d1.y() * d2.x());
  }
  return a;
}

Vec2 Mesh2D::centroid(int e) const {
  const auto& q = quads[e];
  return 0.25 * (nodes[q[0]] + nodes[q[1]] + nodes[q[2]] + nodes[q[3]]);
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

// ---------------------------------------------------------------- Gmsh 4.x ASCII reader
namespace {

struct Reader {
  std::istream& in;
  const std::string& file;
  int line = 0;
  std::string next_line() {
    std::string s;
    if (!std::getline(in, s)) fail("unexpected end of file");
    ++line;
    if (!s.empty() && s.back() == '\r') s.pop_back();
    return s;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(file, "line " + std::to_string(line), what);
  }
  template <class... T>
  void parse(const std::string& s, T&... out) {
    std::istringstream is(s);
    ((is >> out), ...);
    if (!is) fail("malformed line '" + s + "'");
  }
};

}  // namespace

Mesh2D Mesh2D::read_gmsh(const std::string& path) {
  if (const auto why = unreadable_file_reason(path); !why.empty())
    throw Error(path, "", "mesh file: " + why);
  std::ifstream f(path);
  if (!f) throw Error(path, "", "cannot open mesh file");
  Reader rd{f, path};
  Mesh2D m;
  std::map<int, std::string> phys_names[4];
  std::map<int, std::vector<int>> entity_phys[4];  // entity tag -> physical tags, per dim
  std::map<long, int> node_index;                  // gmsh tag -> our index
  std::map<std::string, std::set<int>> sets;
  bool have_format = false;
  std::string s;
  while (std::getline(f, s)) {
    ++rd.line;
    if (!s.empty() && s.back() == '\r') s.pop_back();
    if (s == "$MeshFormat") {
      double version;
      int file_type, dsize;
      rd.parse(rd.next_line(), version, file_type, dsize);
      if (version < 4.0 || version >= 5.0)
        rd.fail("expected Gmsh format 4.x, got " + std::to_string(version));
      if (file_type != 0) rd.fail("expected an ASCII .msh file (binary given)");
      have_format = true;
    } else if (s == "$PhysicalNames") {
      int n;
      rd.parse(rd.next_line(), n);
      for (int i = 0; i < n; ++i) {
        std::string l = rd.next_line();
        std::istringstream is(l);
        int dim, tag;
        std::string name;
        is >> dim >> tag;
        std::getline(is, name);
        const auto a = name.find('"'), b = name.rfind('"');
        if (!is.eof() && !is) rd.fail("malformed physical name");
        if (a == std::string::npos || b <= a) rd.fail("malformed physical name '" + l + "'");
        if (dim < 0 || dim > 3) rd.fail("bad physical dimension");
        phys_names[dim][tag] = name.substr(a + 1, b - a - 1);
      }
    } else if (s == "$Entities") {
      long np, nc, ns, nv;
      rd.parse(rd.next_line(), np, nc, ns, nv);
      const long counts[4] = {np, nc, ns, nv};
      for (int dim = 0; dim < 4; ++dim)
        for (long i = 0; i < counts[dim]; ++i) {
          std::istringstream is(rd.next_line());
          int tag;
          double x;
          is >> tag;
          const int nbox = dim == 0 ? 3 : 6;
          for (int k = 0; k < nbox; ++k) is >> x;
          long nphys = 0;
          is >> nphys;
          if (!is) rd.fail("malformed entity");
          for (long k = 0; k < nphys; ++k) {
            int p;
            is >> p;
            entity_phys[dim][tag].push_back(std::abs(p));
          }
        }
    } else if (s == "$Nodes") {
      long nblocks, nnodes, minTag, maxTag;
      rd.parse(rd.next_line(), nblocks, nnodes, minTag, maxTag);
      if (nblocks < 0 || nnodes < 0) rd.fail("negative block or node count");
      m.nodes.reserve(
          static_cast<size_t>(std::min(nnodes, 10000000L)));  // a count is a claim, not yet data
      for (long b = 0; b < nblocks; ++b) {
        int edim, etag, parametric;
        long nb;
        rd.parse(rd.next_line(), edim, etag, parametric, nb);
        if (nb < 0) rd.fail("negative node count in a block");
        std::vector<long> tags;
        for (long i = 0; i < nb; ++i) rd.parse(rd.next_line(), tags.emplace_back());
        for (long i = 0; i < nb; ++i) {
          double x, y, z;
          rd.parse(rd.next_line(), x, y, z);
          if (!std::isfinite(x) || !std::isfinite(y)) rd.fail("non-finite node coordinate");
          node_index[tags[i]] = static_cast<int>(m.nodes.size());
          m.nodes.emplace_back(x, y);
        }
      }
    } else if (s == "$Elements") {
      long nblocks, nelem, minTag, maxTag;
      rd.parse(rd.next_line(), nblocks, nelem, minTag, maxTag);
      for (long b = 0; b < nblocks; ++b) {
        int edim, etag, etype;
        long nb;
        rd.parse(rd.next_line(), edim, etag, etype, nb);
        int nn = 0;
        switch (etype) {
          case 15:
            nn = 1;
            break;  // point
          case 1:
            nn = 2;
            break;  // 2-node line
          case 3:
            nn = 4;
            break;  // 4-node quad
          case 2:
            rd.fail(
                "triangles are not supported (lsmbs uses 4-node quadrilaterals: recombine the mesh "
                "in Gmsh)");
          default:
            rd.fail("unsupported element type " + std::to_string(etype) +
                    " (expected points, 2-node lines, 4-node quads)");
        }
        std::vector<std::string> groups;
        if (edim >= 0 && edim < 4 && entity_phys[edim].count(etag))
          for (int p : entity_phys[edim][etag]) {
            if (phys_names[edim].count(p))
              groups.push_back(phys_names[edim][p]);
            else
              groups.push_back("physical_" + std::to_string(p));
          }
        for (long i = 0; i < nb; ++i) {
          std::istringstream is(rd.next_line());
          long tag;
          is >> tag;
          std::array<int, 4> q{};
          for (int k = 0; k < nn; ++k) {
            long nt;
            is >> nt;
            if (!is) rd.fail("malformed element");
            auto it = node_index.find(nt);
            if (it == node_index.end())
              rd.fail("element refers to unknown node " + std::to_string(nt));
            q[k] = it->second;
            if (etype != 3)
              for (const auto& g : groups) sets[g].insert(it->second);
          }
          if (etype == 3) m.quads.push_back(q);
        }
      }
    }
  }
  if (!have_format) throw Error(path, "", "not a Gmsh .msh file ($MeshFormat missing)");
  if (m.quads.empty()) throw Error(path, "", "the mesh contains no 4-node quadrilaterals");
  for (auto& q : m.quads) {  // orient counter-clockwise
    const Vec2 d1 = m.nodes[q[2]] - m.nodes[q[0]], d2 = m.nodes[q[3]] - m.nodes[q[1]];
    if (d1.x() * d2.y() - d1.y() * d2.x() < 0) std::swap(q[1], q[3]);
  }
  // Nodes used by no quad (geometry points such as a bore centre) would carry neither mass
  // nor stiffness: drop them and renumber, keeping node sets consistent.
  std::vector<int> remap(m.nodes.size(), -1);
  for (const auto& q : m.quads)
    for (int k : q) remap[k] = 0;
  std::vector<Vec2> kept;
  for (size_t i = 0; i < m.nodes.size(); ++i)
    if (remap[i] == 0) {
      remap[i] = static_cast<int>(kept.size());
      kept.push_back(m.nodes[i]);
    }
  m.nodes = std::move(kept);
  for (auto& q : m.quads)
    for (int& k : q) k = remap[k];
  for (auto& [name, s2] : sets)
    for (int k : s2)
      if (remap[k] >= 0) m.node_sets[name].push_back(remap[k]);
  return m;
}

}  // namespace lsmbs
