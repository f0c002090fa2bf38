#include "lsmbs/geometry/solid_design_map.hpp"

#include <algorithm>
#include <cmath>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/solid_cell.hpp"

namespace lsmbs {

namespace {

// The logistic's tail beyond this many bands is below e^-30 ≈ 1e-13 (as in design_map.cpp).
constexpr double kTailBands = 30;
// Distances are refined to third order within this many bands (Feature::distance).
constexpr double kRefineBands = 12;

}  // namespace

SolidDesignMap::SolidDesignMap(const SolidMesh& mesh, LevelSet3 level_set, MappingOptions opt)
    : mesh_(&mesh), ls_(std::move(level_set)), opt_(opt) {
  if (auto msg = opt_.validate(); !msg.empty()) throw Error("mapping option " + msg);
  if (opt_.offset != 0)
    throw Error("mapping option offset: the eroded and dilated designs are planar only");
  const int ne = mesh.num_elements();
  volume_.resize(ne);
  radius_.resize(ne);
  centre_.resize(ne);
  std::vector<double> h(ne);
  for (int e = 0; e < ne; ++e) {
    const auto& cell = mesh.cells[static_cast<size_t>(e)];
    Vec3 c = Vec3::Zero();
    for (int k : cell) c += mesh.nodes[static_cast<size_t>(k)];
    c /= static_cast<double>(cell.size());
    double r = 0;
    for (int k : cell) r = std::max(r, (mesh.nodes[static_cast<size_t>(k)] - c).norm());
    volume_[e] = cell_volume(mesh, e);
    // the longest edge, so that the band ε spans `band` sub-cells in every direction of a flat
    // element
    h[e] = longest_edge(mesh, e);
    centre_[e] = c;
    radius_[e] = r;
  }
  std::nth_element(h.begin(), h.begin() + ne / 2, h.end());
  eps_ = opt_.band * h[ne / 2] / opt_.subgrid;
  ls_.set_refine_within(kRefineBands * eps_);
}

void SolidDesignMap::subcells(int e, std::vector<Vec3>& x, std::vector<double>& w) const {
  const int n = opt_.subgrid;
  x.clear(), w.clear();
  const auto& cell = mesh_->cells[static_cast<size_t>(e)];
  if (cell.size() == 8) {
    const double hs = 2.0 / n, w0 = hs * hs * hs;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          double detJ = 0;
          x.push_back(hex_point(*mesh_, e,
                                Vec3(-1 + (i + 0.5) * hs, -1 + (j + 0.5) * hs, -1 + (k + 0.5) * hs),
                                detJ));
          w.push_back(detJ * w0);
        }
    return;
  }
  // the collapsed cube: x = X0 + λ1 (X1 − X0) + λ2 (X2 − X0) + λ3 (X3 − X0), dV = 6V (1−a)²(1−b)
  const Vec3& X0 = mesh_->nodes[static_cast<size_t>(cell[0])];
  const Vec3 e1 = mesh_->nodes[static_cast<size_t>(cell[1])] - X0,
             e2 = mesh_->nodes[static_cast<size_t>(cell[2])] - X0,
             e3 = mesh_->nodes[static_cast<size_t>(cell[3])] - X0;
  const double V6 = 6 * std::abs(volume_[static_cast<size_t>(e)]), hs = 1.0 / n;
  for (int i = 0; i < n; ++i) {
    const double a0 = i * hs, a1 = a0 + hs, a = a0 + hs / 2;
    const double wa = (std::pow(1 - a0, 3) - std::pow(1 - a1, 3)) / 3;
    for (int j = 0; j < n; ++j) {
      const double b0 = j * hs, b1 = b0 + hs, b = b0 + hs / 2;
      const double wb = (std::pow(1 - b0, 2) - std::pow(1 - b1, 2)) / 2;
      for (int k = 0; k < n; ++k) {
        const double c = (k + 0.5) * hs;
        const double l1 = a, l2 = b * (1 - a), l3 = c * (1 - a) * (1 - b);
        x.push_back(X0 + l1 * e1 + l2 * e2 + l3 * e3);
        w.push_back(V6 * wa * wb * hs);
      }
    }
  }
}

void SolidDesignMap::map(const Vec& p, Vec& mu, SpMat* dmu_dp, MapCounts* counts) const {
  const int ne = num_elements();
  const auto theta = ls_.values(p);
  mu.resize(ne);
  std::vector<Eigen::Triplet<double>> trip;
  std::vector<double> col(static_cast<size_t>(ls_.num_variables()));
  std::vector<Vec3> xs;
  std::vector<double> ws;
  LevelSet3::Gradient g;
  const double tail = kTailBands * eps_ + ls_.slack(), mmin = opt_.mu_min;
  MapCounts local;
  for (int e = 0; e < ne; ++e) {
    const double b = ls_.bound(centre_[e], theta, radius_[e]);
    if (std::abs(b) > radius_[e] + tail) {
      mu[e] = b > 0 ? 1.0 : mmin;
      continue;
    }
    ++local.band;
    subcells(e, xs, ws);
    double V = 0, H = 0;
    bool in = false, out = false;
    std::fill(col.begin(), col.end(), 0.0);
    for (size_t s = 0; s < xs.size(); ++s) {
      const double D = ls_.evaluate(xs[s], theta, dmu_dp ? &g : nullptr);
      (D > 0 ? in : out) = true;
      const double h = 1 / (1 + std::exp(-D / eps_));
      V += ws[s];
      H += ws[s] * h;
      if (dmu_dp)
        for (const auto& [k, d] : g) col[static_cast<size_t>(k)] += ws[s] * h * (1 - h) / eps_ * d;
    }
    local.cut += in && out;
    mu[e] = mmin + (1 - mmin) * H / V;
    if (!dmu_dp) continue;
    double big = 0;
    for (double c : col) big = std::max(big, std::abs(c));
    for (size_t k = 0; k < col.size(); ++k)
      if (std::abs(col[k]) > 1e-14 * big && col[k] != 0)
        trip.emplace_back(e, static_cast<int>(k), (1 - mmin) * col[k] / V);
  }
  if (dmu_dp) {
    dmu_dp->resize(ne, ls_.num_variables());
    dmu_dp->setFromTriplets(trip.begin(), trip.end());
  }
  if (counts) *counts = local;
}

std::vector<int> SolidDesignMap::features_outside_mesh(const Vec& p) const {
  const auto theta = ls_.values(p);
  std::vector<int> outside;
  const auto& features = ls_.features();
  for (size_t f = 0; f < features.size(); ++f) {
    bool reaches = false;
    for (int e = 0; e < num_elements() && !reaches; ++e)
      reaches = features[f].bound(centre_[e], theta[f].data(), 0, radius_[e]) <= radius_[e];
    if (!reaches) outside.push_back(static_cast<int>(f));
  }
  return outside;
}

double SolidDesignMap::material_volume(const Vec& mu, const SpMat* dmu, Vec* grad) const {
  const double s = 1 / (1 - opt_.mu_min);
  double V = 0;
  for (int e = 0; e < num_elements(); ++e) V += volume_[e] * (mu[e] - opt_.mu_min) * s;
  if (grad && dmu) {
    grad->setZero(dmu->cols());
    for (int k = 0; k < dmu->outerSize(); ++k)
      for (SpMat::InnerIterator it(*dmu, k); it; ++it)
        (*grad)[it.col()] += volume_[it.row()] * it.value() * s;
  }
  return V;
}

}  // namespace lsmbs
