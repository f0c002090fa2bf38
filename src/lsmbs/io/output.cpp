#include "lsmbs/io/output.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/version.hpp"

namespace lsmbs {

nlohmann::json units_json(const Study& s) {
  nlohmann::json m = nlohmann::json::object(), r = nlohmann::json::object();
  const auto cols = s.measure_columns();
  const auto units = s.measure_units();
  for (size_t i = 0; i < cols.size(); ++i) m[cols[i]] = units[i];
  for (size_t i = 0; i < s.responses.size(); ++i) r[s.responses[i].name] = s.response_unit(i);
  return {{"t", "s"}, {"measures", m}, {"responses", r}};
}

nlohmann::json file_list(std::vector<std::string> files) {
  std::sort(files.begin(), files.end());
  files.erase(std::unique(files.begin(), files.end()), files.end());
  return files;
}

void write_csv(const std::string& path, const std::vector<std::string>& header,
               const std::vector<std::vector<double>>& rows) {
  std::ostringstream os;
  for (size_t i = 0; i < header.size(); ++i) os << (i ? "," : "") << csv_field(header[i]);
  os << "\n";
  for (const auto& r : rows) {
    for (size_t i = 0; i < r.size(); ++i) os << (i ? "," : "") << csv_number(r[i]);
    os << "\n";
  }
  write_file_atomic(path, os.str());
}

void write_vtu(const std::string& path, const FlexibleBody& b, const Vec& q, const ModelParams& p) {
  const int nn = b.mesh.num_nodes(), ne = b.mesh.num_elements();
  std::ostringstream os;
  os << std::setprecision(12);
  os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
        "byte_order=\"LittleEndian\">\n"
     << "<UnstructuredGrid><Piece NumberOfPoints=\"" << nn << "\" NumberOfCells=\"" << ne
     << "\">\n";
  os << "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (int i = 0; i < nn; ++i) os << q[b.node_dof(i)] << " " << q[b.node_dof(i) + 1] << " 0\n";
  os << "</DataArray></Points>\n<Cells>\n<DataArray type=\"Int32\" Name=\"connectivity\" "
        "format=\"ascii\">\n";
  for (const auto& c : b.mesh.quads)
    os << c[0] << " " << c[1] << " " << c[2] << " " << c[3] << "\n";
  os << "</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n";
  for (int e = 1; e <= ne; ++e) os << 4 * e << "\n";
  os << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (int e = 0; e < ne; ++e) os << "9\n";
  // Points are the deformed positions x (the PVD animates the motion as it is). Two vectors:
  // total_displacement x − X (X: the node at t = 0), and elastic_displacement x − (x̄ + R(θ)(X −
  // X̄)), the motion left after the rigid motion that fits the nodes best in least squares
  // (centroids x̄, X̄; θ from the 2-D Procrustes problem). Warp By Vector on elastic_displacement
  // with a factor s shows the deformation magnified s + 1 times; with −1, the body moved rigidly.
  Vec2 xc = Vec2::Zero(), Xc = Vec2::Zero();
  for (int i = 0; i < nn; ++i) {
    xc += q.segment<2>(b.node_dof(i));
    Xc += b.placed(i);
  }
  xc /= nn;
  Xc /= nn;
  double sn = 0, cs = 0;
  for (int i = 0; i < nn; ++i) {
    const Vec2 a = b.placed(i) - Xc, c = q.segment<2>(b.node_dof(i)) - xc;
    sn += a.x() * c.y() - a.y() * c.x();
    cs += a.x() * c.x() + a.y() * c.y();
  }
  const double th = std::atan2(sn, cs), ct = std::cos(th), st = std::sin(th);
  os << "</DataArray>\n</Cells>\n<PointData Vectors=\"elastic_displacement\">\n"
     << "<DataArray type=\"Float64\" Name=\"elastic_displacement\" NumberOfComponents=\"3\" "
        "format=\"ascii\">\n";
  for (int i = 0; i < nn; ++i) {
    const Vec2 a = b.placed(i) - Xc;
    const Vec2 u =
        q.segment<2>(b.node_dof(i)) - xc - Vec2(ct * a.x() - st * a.y(), st * a.x() + ct * a.y());
    os << u.x() << " " << u.y() << " 0\n";
  }
  os << "</DataArray>\n<DataArray type=\"Float64\" Name=\"total_displacement\" "
        "NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (int i = 0; i < nn; ++i) {
    const Vec2 u = q.segment<2>(b.node_dof(i)) - b.placed(i);
    os << u.x() << " " << u.y() << " 0\n";
  }
  os << "</DataArray>\n</PointData>\n<CellData Scalars=\"mu\">\n"
     << "<DataArray type=\"Float64\" Name=\"mu\" format=\"ascii\">\n";
  const Vec& mu = p.fields[b.field];
  for (int e = 0; e < ne; ++e) os << mu[e] << "\n";
  os << "</DataArray>\n<DataArray type=\"Float64\" Name=\"von_mises\" format=\"ascii\">\n";
  const double E0 = p.scalars[b.E_param], nu = p.scalars[b.nu_param];
  for (int e = 0; e < ne; ++e) {
    QuadElement::Vec8 x;
    for (int k = 0; k < 4; ++k) x.segment<2>(2 * k) = q.segment<2>(b.node_dof(b.mesh.quads[e][k]));
    Eigen::Vector3d Ev;
    Mat2 F;
    b.elements[e].centre_strain(x, Ev, F);
    const double E = mu[e] * E0, c = E / (1 - nu * nu);
    Mat2 S;
    S << c * (Ev[0] + nu * Ev[1]), c * (1 - nu) / 2 * Ev[2], c * (1 - nu) / 2 * Ev[2],
        c * (Ev[1] + nu * Ev[0]);
    const Mat2 sig = F * S * F.transpose() / F.determinant();
    const double vm = std::sqrt(sig(0, 0) * sig(0, 0) - sig(0, 0) * sig(1, 1) +
                                sig(1, 1) * sig(1, 1) + 3 * sig(0, 1) * sig(0, 1));
    os << vm << "\n";
  }
  os << "</DataArray>\n</CellData>\n</Piece></UnstructuredGrid>\n</VTKFile>\n";
  write_file_atomic(path, os.str());
}

void write_design_vtu(const std::string& path, const Mesh2D& mesh, const Vec& mu, const Vec& phi) {
  const int nn = mesh.num_nodes(), ne = mesh.num_elements();
  std::ostringstream os;
  os << std::setprecision(17);
  os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
        "byte_order=\"LittleEndian\">\n"
     << "<UnstructuredGrid><Piece NumberOfPoints=\"" << nn << "\" NumberOfCells=\"" << ne
     << "\">\n<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const auto& x : mesh.nodes) os << x.x() << " " << x.y() << " 0\n";
  os << "</DataArray></Points>\n<Cells>\n<DataArray type=\"Int32\" Name=\"connectivity\" "
        "format=\"ascii\">\n";
  for (const auto& c : mesh.quads) os << c[0] << " " << c[1] << " " << c[2] << " " << c[3] << "\n";
  os << "</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n";
  for (int e = 1; e <= ne; ++e) os << 4 * e << "\n";
  os << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (int e = 0; e < ne; ++e) os << "9\n";
  os << "</DataArray>\n</Cells>\n<PointData Scalars=\"phi\">\n"
     << "<DataArray type=\"Float64\" Name=\"phi\" format=\"ascii\">\n";
  for (int i = 0; i < nn; ++i) os << phi[i] << "\n";
  os << "</DataArray>\n</PointData>\n<CellData Scalars=\"mu\">\n"
     << "<DataArray type=\"Float64\" Name=\"mu\" format=\"ascii\">\n";
  for (int e = 0; e < ne; ++e) os << mu[e] << "\n";
  os << "</DataArray>\n</CellData>\n</Piece></UnstructuredGrid>\n</VTKFile>\n";
  write_file_atomic(path, os.str());
}

void write_pvd(const std::string& path,
               const std::vector<std::pair<double, std::string>>& entries) {
  std::ostringstream os;
  os << std::setprecision(12);
  os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  for (const auto& [t, f] : entries)
    os << "<DataSet timestep=\"" << t << "\" file=\"" << f << "\"/>\n";
  os << "</Collection>\n</VTKFile>\n";
  write_file_atomic(path, os.str());
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
