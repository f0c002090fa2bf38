#include "lsmbs/io/output.hpp"

#include <unistd.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/core/version.hpp"
#include "lsmbs/fem/element_types.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/mbs/spatial.hpp"

namespace lsmbs {

nlohmann::json units_json(const Study& s) {
  nlohmann::json m = nlohmann::json::object(), r = nlohmann::json::object();
  const auto cols = s.measure_columns();
  const auto units = s.measure_units();
  for (size_t i = 0; i < cols.size(); ++i) m[cols[i]] = units[i];
  for (size_t i = 0; i < s.responses.size(); ++i) r[s.responses[i].name] = s.response_unit(i);
  return {{"t", "s"}, {"measures", m}, {"responses", r}};
}

nlohmann::json units_json(const Conditions& c) {
  nlohmann::json j = units_json(c.first());
  if (!c.several() && c.combinations.empty()) return j;
  nlohmann::json r = nlohmann::json::object();
  for (const auto& name : c.response_names()) r[name] = c.unit(name);
  j["responses"] = r;
  return j;
}

nlohmann::json conditions_json(const Case& cs, const Conditions& c) {
  nlohmann::json conds = nlohmann::json::array();
  for (size_t k = 0; k < cs.conditions.size(); ++k) {
    const auto& raw = cs.raw.at("conditions").at(k);
    conds.push_back({{"name", c.names[k]},
                     {"set", raw.contains("set") ? raw.at("set") : nlohmann::json::object()},
                     {"t_end", c.studies[k]->simulation.t_end},
                     {"h", c.studies[k]->simulation.h}});
  }
  nlohmann::json comb = nlohmann::json::array();
  for (const auto& x : c.combinations) {
    nlohmann::json e = {
        {"name", x.name}, {"aggregate", ResponseCombination::kind_name(x.kind)}, {"of", x.of}};
    if (!x.weights.empty()) e["weights"] = x.weights;
    if (x.kind == ResponseCombination::Kind::kKs) {
      e["ks"] = x.ks;
      e["error_bound"] = x.error_bound();
      e["error_definition"] = "max <= ks <= max + ln(n)/ks, in the responses' unit";
    }
    comb.push_back(e);
  }
  nlohmann::json once = nlohmann::json::array();  // evaluated in the first condition only
  if (c.several())
    for (size_t r = 0; r < c.first().responses.size(); ++r)
      if (Conditions::state_independent(c.first(), r)) once.push_back(c.first().responses[r].name);
  return {{"conditions", conds},
          {"combined", comb},
          {"state_independent_responses", once},
          {"responses", c.response_names()}};
}

nlohmann::json file_list(std::vector<std::string> files) {
  std::sort(files.begin(), files.end());
  files.erase(std::unique(files.begin(), files.end()), files.end());
  return files;
}

void write_csv(const std::string& path, const std::vector<std::string>& header,
               const std::vector<std::vector<double>>& rows, const std::function<void()>& poll) {
  std::ostringstream os;
  for (size_t i = 0; i < header.size(); ++i) os << (i ? "," : "") << csv_field(header[i]);
  os << "\n";
  size_t n = 0;
  for (const auto& r : rows) {
    if (poll && ++n % 4096 == 0) poll();
    for (size_t i = 0; i < r.size(); ++i) os << (i ? "," : "") << csv_number(r[i]);
    os << "\n";
  }
  write_file_atomic(path, os.str());
}

namespace {

std::string xml_attribute(const std::string& text);

// One data array of a VTU piece: `components` values per point or cell.
struct VtuArray {
  std::string name;
  int components = 1;
  std::vector<double> values;
};

// The one unstructured-grid writer: points (z = 0), cells (VTK connectivity, offsets and types),
// point and cell data, ASCII with 17 significant digits (every double reads back exactly). The
// first array of each kind is the active one (Vectors when it has 3 components, else Scalars).
struct VtuPiece {
  std::vector<Vec2> points;
  std::vector<double> z;                   // per point, when the piece is spatial (empty: z = 0)
  std::vector<int> connectivity, offsets;  // offsets: the end of each cell in connectivity
  std::vector<int> types;                  // VTK cell types: 1 vertex, 3 line, 7 polygon, 9 quad
  std::vector<VtuArray> point_data, cell_data;

  void add_cell(std::initializer_list<int> nodes, int type) {
    add_cell(nodes.begin(), nodes.end(), type);
  }
  template <class It>
  void add_cell(It first, It last, int type) {
    connectivity.insert(connectivity.end(), first, last);
    offsets.push_back(static_cast<int>(connectivity.size()));
    types.push_back(type);
  }

  void write(const std::string& path) const {
    std::ostringstream os;
    os << std::setprecision(17);
    os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
          "byte_order=\"LittleEndian\">\n<UnstructuredGrid><Piece NumberOfPoints=\""
       << points.size() << "\" NumberOfCells=\"" << types.size() << "\">\n"
       << "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (size_t i = 0; i < points.size(); ++i)
      os << points[i].x() << " " << points[i].y() << " " << (z.empty() ? 0.0 : z[i]) << "\n";
    os << "</DataArray></Points>\n<Cells>\n"
       << "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n";
    for (size_t c = 0; c < offsets.size(); ++c) {  // one cell a line
      const int first = c ? offsets[c - 1] : 0;
      for (int k = first; k < offsets[c]; ++k) os << (k > first ? " " : "") << connectivity[k];
      os << "\n";
    }
    os << "</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n";
    for (int o : offsets) os << o << "\n";
    os << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
    for (int t : types) os << t << "\n";
    os << "</DataArray>\n</Cells>\n";
    data(os, "PointData", point_data);
    data(os, "CellData", cell_data);
    os << "</Piece></UnstructuredGrid>\n</VTKFile>\n";
    write_file_atomic(path, os.str());
  }

 private:
  static void data(std::ostringstream& os, const char* tag, const std::vector<VtuArray>& arrays) {
    if (arrays.empty()) return;
    const VtuArray& a0 = arrays.front();
    os << "<" << tag << " " << (a0.components == 3 ? "Vectors" : "Scalars") << "=\""
       << xml_attribute(a0.name) << "\">\n";
    for (const auto& a : arrays) {
      os << "<DataArray type=\"Float64\" Name=\"" << xml_attribute(a.name) << "\"";
      if (a.components > 1) os << " NumberOfComponents=\"" << a.components << "\"";
      os << " format=\"ascii\">\n";
      for (size_t i = 0; i < a.values.size(); ++i)
        os << a.values[i] << ((i + 1) % static_cast<size_t>(a.components) == 0 ? "\n" : " ");
      os << "</DataArray>\n";
    }
    os << "</" << tag << ">\n";
  }
};

// a 2-D vector field as a VTK 3-vector array (z = 0)
VtuArray vectors(const std::string& name, const std::vector<Vec2>& v) {
  VtuArray a{name, 3, {}};
  a.values.reserve(3 * v.size());
  for (const auto& x : v) a.values.insert(a.values.end(), {x.x(), x.y(), 0.0});
  return a;
}

// An XML attribute value: UTF-8 without control characters (XML 1.0 allows none of them, not even
// as character references), and the markup characters escaped.
std::string xml_attribute(const std::string& text) {
  const std::string s = displayable_text(text, std::string::npos);
  std::string r;
  for (char c : s) {
    if (c == '&')
      r += "&amp;";
    else if (c == '<')
      r += "&lt;";
    else if (c == '>')
      r += "&gt;";
    else if (c == '"')
      r += "&quot;";
    else
      r += c;
  }
  return r;
}

}  // namespace

void write_vtu(const std::string& path, const FlexibleBody& b, const Vec& q, const ModelParams& p,
               const CellArrays& cells) {
  const int nn = b.mesh.num_nodes(), ne = b.mesh.num_elements();
  VtuPiece v;
  for (int i = 0; i < nn; ++i) v.points.push_back(q.segment<2>(b.node_dof(i)));
  for (const auto& c : b.mesh.cells) v.add_cell(c.begin(), c.end(), element_type(c.type).vtk_type);
  // Points are the deformed positions x (the PVD animates the motion as it is). Two vectors:
  // total_displacement x − X (X: the node at t = 0), and elastic_displacement x − (x̄ + R(θ)(X −
  // X̄)), the motion left after the rigid motion that fits the nodes best in least squares
  // (centroids x̄, X̄; θ from the 2-D Procrustes problem). Warp By Vector on elastic_displacement
  // with a factor s shows the deformation magnified s + 1 times; with −1, the body moved rigidly.
  Vec2 xc = Vec2::Zero(), Xc = Vec2::Zero();
  for (int i = 0; i < nn; ++i) {
    xc += v.points[i];
    Xc += b.placed(i);
  }
  xc /= nn;
  Xc /= nn;
  double sn = 0, cs = 0;
  for (int i = 0; i < nn; ++i) {
    const Vec2 a = b.placed(i) - Xc, c = v.points[i] - xc;
    sn += a.x() * c.y() - a.y() * c.x();
    cs += a.x() * c.x() + a.y() * c.y();
  }
  const Mat2 R = rotation(std::atan2(sn, cs));
  std::vector<Vec2> elastic(nn), total(nn);
  for (int i = 0; i < nn; ++i) {
    elastic[i] = v.points[i] - xc - R * (b.placed(i) - Xc);
    total[i] = v.points[i] - b.placed(i);
  }
  v.point_data = {vectors("elastic_displacement", elastic), vectors("total_displacement", total)};
  const Vec& mu = p.fields[b.field];
  VtuArray vm{"von_mises", 1, {}};
  const double E0 = p.scalars[b.E_param], nu = p.scalars[b.nu_param];
  double x[kMaxLocalDofs];
  for (int e = 0; e < ne; ++e) {
    b.element_coordinates(e, q, x);
    Eigen::Vector3d Ev;
    Mat2 F;
    b.elements[e]->centre_strain(x, Ev, F);
    const double E = mu[e] * E0, c = E / (1 - nu * nu);
    Mat2 S;
    S << c * (Ev[0] + nu * Ev[1]), c * (1 - nu) / 2 * Ev[2], c * (1 - nu) / 2 * Ev[2],
        c * (Ev[1] + nu * Ev[0]);
    const Mat2 sig = F * S * F.transpose() / F.determinant();
    vm.values.push_back(std::sqrt(sig(0, 0) * sig(0, 0) - sig(0, 0) * sig(1, 1) +
                                  sig(1, 1) * sig(1, 1) + 3 * sig(0, 1) * sig(0, 1)));
  }
  v.cell_data = {{"mu", 1, std::vector<double>(mu.data(), mu.data() + ne)}, std::move(vm)};
  for (const auto& [name, values] : cells) v.cell_data.push_back({name, 1, values});
  v.write(path);
}

std::vector<Vec2> rigid_outline(const RigidBody& b) {
  std::vector<Vec2> pts = b.attachments;
  if (b.com_offset != Vec2::Zero()) pts.push_back(b.com_offset);
  if (pts.empty()) return {Vec2::Zero()};
  // Andrew's monotone chain; cross ≤ 0 pops, so collinear points drop out
  std::sort(pts.begin(), pts.end(), [](const Vec2& a, const Vec2& c) {
    return a.x() < c.x() || (a.x() == c.x() && a.y() < c.y());
  });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  auto cross = [](const Vec2& o, const Vec2& a, const Vec2& c) {
    return (a.x() - o.x()) * (c.y() - o.y()) - (a.y() - o.y()) * (c.x() - o.x());
  };
  std::vector<Vec2> hull(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {  // lower chain
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, lower = k + 1; i-- > 0;) {  // upper chain
    while (k >= lower && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);  // the last point is the first again
  return hull;
}

void write_rigid_vtu(const std::string& path, const RigidBody& b, const Vec& q) {
  const std::vector<Vec2> d = rigid_outline(b);
  const Vec2 r = q.segment<2>(b.dof0);
  const Mat2 R = rotation(q[b.dof0 + 2]), R0 = rotation(b.angle0);
  VtuPiece v;
  std::vector<Vec2> total;
  std::vector<int> cell;
  for (const auto& di : d) {
    cell.push_back(static_cast<int>(v.points.size()));
    v.points.push_back(r + R * di);
    total.push_back(v.points.back() - (b.position0 + R0 * di));
  }
  v.add_cell(cell.begin(), cell.end(), d.size() == 1 ? 1 : d.size() == 2 ? 3 : 7);
  v.point_data = {vectors("elastic_displacement", std::vector<Vec2>(d.size(), Vec2::Zero())),
                  vectors("total_displacement", total)};
  v.write(path);
}

void write_spatial_vtu(const std::string& path, const SpatialRigidBody& b, const Vec& q) {
  // the centre of mass, a line to each attachment and the principal axes (lines of a tenth of
  // the body's reach, at least 1 cm), placed by the natural coordinates at q
  const SpatialPose P = SpatialPose::read(b.dof0, q);
  const SpatialPose P0{b.position0, b.orientation0};
  double reach = 0;
  for (const auto& d : b.attachments) reach = std::max(reach, d.norm());
  const double axis = std::max(0.1 * reach, 0.01);
  std::vector<Vec3> local = {Vec3::Zero()};
  for (const auto& d : b.attachments) local.push_back(d);
  for (int k = 0; k < 3; ++k) local.push_back(axis * Vec3::Unit(k));
  VtuPiece v;
  VtuArray total{"total_displacement", 3, {}}, elastic{"elastic_displacement", 3, {}};
  for (const auto& d : local) {
    const Vec3 x = P.r + P.R * d, x0 = P0.r + P0.R * d;
    v.points.emplace_back(x.x(), x.y());
    v.z.push_back(x.z());
    total.values.insert(total.values.end(), {x.x() - x0.x(), x.y() - x0.y(), x.z() - x0.z()});
    elastic.values.insert(elastic.values.end(), {0.0, 0.0, 0.0});
  }
  VtuArray part{"part", 1, {}};  // 0 the centre of mass, 1 a link to an attachment, 2 an axis
  v.add_cell({0}, 1);
  part.values.push_back(0);
  const int n = static_cast<int>(b.attachments.size());
  for (int i = 1; i <= n; ++i) {
    v.add_cell({0, i}, 3);
    part.values.push_back(1);
  }
  for (int k = 0; k < 3; ++k) {
    v.add_cell({0, n + 1 + k}, 3);
    part.values.push_back(2);
  }
  v.point_data = {elastic, total};
  v.cell_data = {part};
  v.write(path);
}

void write_solid_vtu(const std::string& path, const SolidBody& b, const Vec& q,
                     const ModelParams& p, const Vec* phi) {
  const int nn = b.mesh.num_nodes(), ne = b.mesh.num_elements();
  VtuPiece v;
  std::vector<Vec3> x(static_cast<size_t>(nn));
  Vec3 xc = Vec3::Zero(), Xc = Vec3::Zero();
  for (int i = 0; i < nn; ++i) {
    x[static_cast<size_t>(i)] = q.segment<3>(b.node_dof(i));
    v.points.emplace_back(x[static_cast<size_t>(i)].x(), x[static_cast<size_t>(i)].y());
    v.z.push_back(x[static_cast<size_t>(i)].z());
    xc += x[static_cast<size_t>(i)];
    Xc += b.mesh.nodes[static_cast<size_t>(i)];
  }
  xc /= nn;
  Xc /= nn;
  for (const auto& c : b.mesh.cells) v.add_cell(c.begin(), c.end(), c.size() == 8 ? 12 : 10);
  // the rotation that fits the nodes best (Kabsch: R = V diag(1, 1, det) Uᵀ of the covariance)
  Mat3 H = Mat3::Zero();
  for (int i = 0; i < nn; ++i)
    H += (b.mesh.nodes[static_cast<size_t>(i)] - Xc) * (x[static_cast<size_t>(i)] - xc).transpose();
  const Eigen::JacobiSVD<Mat3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 D = Mat3::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  const Mat3 R = svd.matrixV() * D * svd.matrixU().transpose();
  VtuArray total{"total_displacement", 3, {}}, elastic{"elastic_displacement", 3, {}};
  for (int i = 0; i < nn; ++i) {
    const Vec3& X = b.mesh.nodes[static_cast<size_t>(i)];
    const Vec3 t = x[static_cast<size_t>(i)] - X, e = x[static_cast<size_t>(i)] - xc - R * (X - Xc);
    total.values.insert(total.values.end(), {t.x(), t.y(), t.z()});
    elastic.values.insert(elastic.values.end(), {e.x(), e.y(), e.z()});
  }
  const Vec& mu = p.fields[static_cast<size_t>(b.field)];
  const double E0 = p.scalars[static_cast<size_t>(b.E_param)];
  const double nu = p.scalars[static_cast<size_t>(b.nu_param)];
  VtuArray vm{"von_mises", 1, {}};
  double xe[kMaxLocalDofs];
  for (int e = 0; e < ne; ++e) {
    const auto& c = b.mesh.cells[static_cast<size_t>(e)];
    for (size_t k = 0; k < c.size(); ++k)
      for (int i = 0; i < 3; ++i) xe[3 * k + static_cast<size_t>(i)] = q[b.node_dof(c[k]) + i];
    const SolidElement& el = *b.elements[static_cast<size_t>(e)];
    const auto S = el.centre_stress(xe, E0, nu);  // solid material, as the planar picture
    const Mat3 F = el.centre_F(xe);
    Mat3 St;
    St << S[0], S[3], S[5], S[3], S[1], S[4], S[5], S[4], S[2];
    const Mat3 sig = F * St * F.transpose() / F.determinant();
    const Mat3 dev = sig - sig.trace() / 3 * Mat3::Identity();
    vm.values.push_back(std::sqrt(1.5 * dev.squaredNorm()));
  }
  v.point_data = {elastic, total};
  if (phi) v.point_data.push_back({"phi", 1, std::vector<double>(phi->data(), phi->data() + nn)});
  v.cell_data = {{"mu", 1, std::vector<double>(mu.data(), mu.data() + ne)}, std::move(vm)};
  v.write(path);
}

void write_design_vtu(const std::string& path, const Mesh2D& mesh, const Vec& mu, const Vec& phi) {
  VtuPiece v;
  v.points = mesh.nodes;
  for (const auto& c : mesh.cells) v.add_cell(c.begin(), c.end(), element_type(c.type).vtk_type);
  v.point_data = {{"phi", 1, std::vector<double>(phi.data(), phi.data() + phi.size())}};
  v.cell_data = {{"mu", 1, std::vector<double>(mu.data(), mu.data() + mu.size())}};
  v.write(path);
}

void write_vtm(const std::string& path,
               const std::vector<std::pair<std::string, std::string>>& blocks) {
  std::ostringstream os;
  os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"vtkMultiBlockDataSet\" version=\"1.0\" "
        "byte_order=\"LittleEndian\">\n<vtkMultiBlockDataSet>\n";
  for (size_t i = 0; i < blocks.size(); ++i)
    os << "<DataSet index=\"" << i << "\" name=\"" << xml_attribute(blocks[i].first) << "\" file=\""
       << xml_attribute(blocks[i].second) << "\"/>\n";
  os << "</vtkMultiBlockDataSet>\n</VTKFile>\n";
  write_file_atomic(path, os.str());
}

ModelVtkFiles write_model_vtk(const std::string& out_dir, const std::string& folder,
                              const std::string& suffix, const Model& m, const ModelParams& params,
                              const Vec& q, const std::vector<const StressMeasure*>& stress) {
  ModelVtkFiles f;
  std::vector<std::pair<std::string, std::string>> blocks;  // relative to the .vtm
  const auto stems = body_file_stems(m);
  auto add = [&](const std::string& name) {
    const std::string file = stems.at(name) + suffix + ".vtu";
    blocks.emplace_back(name, file);
    f.bodies.emplace_back(name, folder + file);
    return out_dir + "/" + folder + file;
  };
  for (const auto& b : m.flexible_bodies()) {
    CellArrays cells;
    for (const StressMeasure* sm : stress)
      if (sm->flexible() == b.get()) {
        State s;
        s.q = q;
        std::vector<double> se;
        sm->element_stresses(s, params, se);
        cells.emplace_back(sm->name() + "_relaxed_von_mises", std::move(se));
      }
    write_vtu(add(b->name), *b, q, params, cells);
  }
  for (const auto& b : m.rigid_bodies()) write_rigid_vtu(add(b.name), b, q);
  for (const auto& b : m.spatial_bodies()) write_spatial_vtu(add(b.name), b, q);
  for (const auto& b : m.solid_bodies()) write_solid_vtu(add(b->name), *b, q, params);
  f.multiblock = folder + kModelVtk + suffix + ".vtm";
  write_vtm(out_dir + "/" + f.multiblock, blocks);
  return f;
}

std::map<std::string, std::string> body_file_stems(const Model& m) {
  std::map<std::string, std::string> stems;
  std::set<std::string> taken = {kModelVtk};
  auto add = [&](const std::string& name) {
    const std::string base = file_stem(name);
    std::string stem = base;
    for (int k = 2; taken.count(stem); ++k) stem = base + "_" + std::to_string(k);
    taken.insert(stem);
    stems[name] = stem;
  };
  for (const auto& b : m.flexible_bodies()) add(b->name);
  for (const auto& b : m.rigid_bodies()) add(b.name);
  for (const auto& b : m.spatial_bodies()) add(b.name);
  for (const auto& b : m.solid_bodies()) add(b->name);
  return stems;
}

void write_pvd(const std::string& path,
               const std::vector<std::pair<double, std::string>>& entries) {
  std::ostringstream os;
  os << std::setprecision(15);  // t to 15 digits: grid times print as they were given
  os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  for (const auto& [t, f] : entries)
    os << "<DataSet timestep=\"" << t << "\" file=\"" << xml_attribute(f) << "\"/>\n";
  os << "</Collection>\n</VTKFile>\n";
  write_file_atomic(path, os.str());
}

nlohmann::json design_json(const Study& s, const Vec& p) {
  if (!s.design) return nullptr;
  const Vec x = p.size() ? p : s.design->initial();
  nlohmann::json d = nlohmann::json::object();
  for (int i = 0; i < s.design->size(); ++i) d[s.design->variables[i].name] = x[i];
  return d;
}

nlohmann::json provenance(const std::string& command, const std::string& case_file,
                          const std::string& sha) {
  char buf[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  return {{"program", "lsmbs"}, {"version", kVersion},    {"git_commit", git_commit()},
          {"command", command}, {"case_file", case_file}, {"case_sha256", sha},
          {"created_utc", buf}};
}

}  // namespace lsmbs
