#include "lsmbs/geometry/design_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/element_types.hpp"

namespace lsmbs {

// The logistic's tail beyond this many bands is below e^-30 ≈ 1e-13: elements farther from every
// boundary are uniform to round-off, and distances there need no refinement.
constexpr double kTailBands = 30;
// Distances are refined to third order within this many bands (blended C² from half of it, where
// the logistic's weight is already below e^-6): far from a slender feature the Newton projection
// is not reliable (at 30 bands it flipped signs on the robot arm's plate edges).
constexpr double kRefineBands = 12;
// An offset contour lies several elements from the features' own: their distances there are made
// exact by foot-point iterations (Feature::distance). 8 bring the area of a ξ = 5 super-ellipse
// grown by one 5 mm element to Steiner's parallel area (tests/unit/geometry/design_map_test.cpp).
constexpr int kOffsetFootIterations = 8;

std::string MappingOptions::validate() const {
  if (!(mu_min > 0 && mu_min < 1)) return "mu_min: expected a minimum volume fraction in (0, 1)";
  if (subgrid < 1 || subgrid > 1024) return "subgrid: expected 1..1024 sub-cells per element edge";
  if (!(band > 0) || !std::isfinite(band)) return "band: expected a positive width (in sub-cells)";
  if (!std::isfinite(offset)) return "offset: expected a finite length [m]";
  return {};
}

DesignMap::DesignMap(const Mesh2D& mesh, LevelSet level_set, MappingOptions opt)
    : mesh_(&mesh), ls_(std::move(level_set)), opt_(opt) {
  if (auto msg = opt_.validate(); !msg.empty()) throw Error("mapping option " + msg);
  const int ne = mesh.num_elements();
  area_.resize(ne);
  radius_.resize(ne);
  std::vector<double> h(ne);
  for (int e = 0; e < ne; ++e) {
    const Cell& q = mesh.cells[static_cast<size_t>(e)];
    area_[e] = element_type(q.type).shape->area(mesh.cell_nodes(e).data());
    const Vec2 c = mesh.centroid(e);
    double r = 0;
    for (int k : q) r = std::max(r, (mesh.nodes[k] - c).norm());
    radius_[e] = r;
    h[e] = std::sqrt(area_[e]);
  }
  std::nth_element(h.begin(), h.begin() + ne / 2, h.end());
  eps_ = opt_.band * h[ne / 2] / opt_.subgrid;
  // an offset boundary lies |offset| from the zero level: refined with room on either side
  ls_.set_refine_within(kRefineBands * eps_ + 2 * std::abs(opt_.offset));
  if (opt_.offset != 0) ls_.set_foot_iterations(kOffsetFootIterations);
}

std::vector<int> DesignMap::features_outside_mesh(const Vec& p) const {
  const auto vals = ls_.values(p);
  const auto& features = ls_.features();
  std::vector<int> outside;
  for (size_t f = 0; f < features.size(); ++f) {
    const Feature& F = features[f];
    bool reaches = false;
    for (int e = 0; e < num_elements() && !reaches; ++e) {
      const double d = ls_.feature_distance(static_cast<int>(f), mesh_->centroid(e), vals, nullptr);
      // the distance from the shape: positive outside it, for holes and solid features alike
      reaches = (F.hole() ? d : -d) <= radius_[e];
    }
    if (!reaches) outside.push_back(static_cast<int>(f));
  }
  return outside;
}

bool DesignMap::disc_can_reach_mesh(const Vec2& lo, const Vec2& hi, double radius) const {
  for (int e = 0; e < num_elements(); ++e) {
    const Vec2 c = mesh_->centroid(e);
    const Vec2 nearest = c.cwiseMax(lo).cwiseMin(hi);  // the box's point nearest to c
    if ((c - nearest).norm() - radius <= radius_[e]) return true;
  }
  return false;
}

void DesignMap::map(const Vec& p, Vec& mu, SpMat* dmu_dp, MapCounts* counts) const {
  const int ne = num_elements(), nv = ls_.num_variables();
  const int nf = static_cast<int>(ls_.features().size());
  const auto vals = ls_.values(p);
  mu.resize(ne);
  std::vector<Eigen::Triplet<double>> trip;
  LevelSet::Gradient grad;
  std::vector<double> acc(static_cast<size_t>(nv), 0.0);
  std::vector<int> touched;
  std::vector<double> frozen(static_cast<size_t>(nf));
  std::vector<bool> exact(static_cast<size_t>(nf));
  for (int f = 0; f < nf; ++f)
    exact[static_cast<size_t>(f)] =
        ls_.features()[static_cast<size_t>(f)].exact_distance(vals.theta[static_cast<size_t>(f)]);
  const double cut_dist = kTailBands * eps_;
  const int n = opt_.subgrid;
  // the level set D − offset (MappingOptions::offset)
  auto level = [&](const Vec2& x, LevelSet::Gradient* g, const double* fz) {
    return ls_.evaluate(x, vals, g, fz) - opt_.offset;
  };
  int cut = 0, band = 0;
  long frozen_pairs = 0;
  std::vector<CellSample> samples;
  for (int e = 0; e < ne; ++e) {
    const Cell& q = mesh_->cells[static_cast<size_t>(e)];
    // classification
    const Vec2 c = mesh_->centroid(e);
    const double dc = level(c, nullptr, nullptr);
    double dmin = std::abs(dc);
    bool uniform = true;
    for (int k : q) {
      const double d = level(mesh_->nodes[k], nullptr, nullptr);
      if ((d > 0) != (dc > 0)) uniform = false;
      dmin = std::min(dmin, std::abs(d));
    }
    if (uniform && dmin > radius_[e] + cut_dist) {
      mu[e] = dc > 0 ? 1.0 : opt_.mu_min;
      continue;
    }
    ++band;
    // a boundary crosses the element when its samples (corners, centre, sub-cell centres) are
    // on both sides of it
    bool inside = dc > 0, outside = dc <= 0;
    for (int k : q) (level(mesh_->nodes[k], nullptr, nullptr) > 0 ? inside : outside) = true;
    // Features far from the element are frozen at their centre value on its sub-cells: a feature
    // whose distance is exact (Feature::exact_distance: it changes by at most |Δx|) and exceeds,
    // at the centre, twice the element's circumradius + the logistic's tail (+ the offset) keeps
    // its sign over the element and stays beyond the tail, so wherever it is the active child of
    // an exact min/max, H* is 0 or 1 and H*' is 0 to e^-30. (A child of a KS and/or weighs in at
    // every distance: never frozen.) The cost per sub-cell then grows with the features near
    // the element only (the test FrozenFarFeaturesChangeNothing compares with freezing off).
    // A super-ellipse's D₀ = φ/|∇φ| is not a distance; it is frozen where a lower bound of |D₀|
    // over the element's disc (Feature::far_bound) exceeds the tail and the refinement radius,
    // so that distance() is D₀ throughout, of one sign and beyond the tail.
    for (int f = 0; f < nf; ++f) {
      double& fz = frozen[static_cast<size_t>(f)];
      fz = std::numeric_limits<double>::quiet_NaN();
      if (!freeze_far_features_ || ls_.smoothed(f)) continue;
      const auto& th = vals.theta[static_cast<size_t>(f)];
      const auto& F = ls_.features()[static_cast<size_t>(f)];
      if (exact[static_cast<size_t>(f)]) {
        const double d = ls_.feature_distance(f, c, vals, nullptr);
        if (std::abs(d) > 2 * radius_[e] + cut_dist + std::abs(opt_.offset)) fz = d;
      } else if (F.type() == Feature::Type::kSuperEllipse) {
        const double L = std::abs(F.far_bound(c, radius_[e], th));
        if (L > cut_dist + std::abs(opt_.offset) && L >= ls_.refine_within())
          fz = ls_.feature_distance(f, c, vals, nullptr);
      }
      frozen_pairs += !std::isnan(fz);
    }
    // sub-cell integration over the cell, midpoint rule per sub-cell (CellShape::samples)
    samples.clear();
    element_type(q.type).shape->samples(mesh_->cell_nodes(e).data(), n, samples);
    double H = 0, W = 0;
    for (const CellSample& smp : samples) {
      const double w = smp.w;
      const double D = level(smp.x, dmu_dp ? &grad : nullptr, frozen.data());
      (D > 0 ? inside : outside) = true;
      const double z = D / eps_;
      // logistic H*(D) and its derivative, written to stay finite for large |z|
      const double ez = std::exp(-std::abs(z));
      const double h = z >= 0 ? 1 / (1 + ez) : ez / (1 + ez);
      const double dh = ez / ((1 + ez) * (1 + ez)) / eps_;
      H += w * h;
      W += w;
      if (dmu_dp)
        for (const auto& [k, g] : grad) {
          double& a = acc[static_cast<size_t>(k)];
          if (a == 0) touched.push_back(k);
          a += w * dh * g;
        }
    }
    cut += inside && outside;
    const double s = (1 - opt_.mu_min) / W;
    mu[e] = opt_.mu_min + s * H;
    if (dmu_dp) {
      std::sort(touched.begin(), touched.end());
      touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
      for (int k : touched) {
        double& a = acc[static_cast<size_t>(k)];
        if (a != 0) trip.emplace_back(e, k, s * a);
        a = 0;
      }
      touched.clear();
    }
  }
  if (dmu_dp) {
    // Entries below 1e-12 of their column's largest come from the logistic's far tail (e^-27):
    // dropping them keeps ∂μ/∂p sparse (only elements a boundary really crosses) at a relative
    // cost below 1e-12 per entry. μ itself is not truncated.
    std::vector<double> colmax(nv, 0.0);
    for (const auto& t : trip) colmax[t.col()] = std::max(colmax[t.col()], std::abs(t.value()));
    std::vector<Eigen::Triplet<double>> kept;
    kept.reserve(trip.size());
    for (const auto& t : trip)
      if (std::abs(t.value()) >= 1e-12 * colmax[t.col()]) kept.push_back(t);
    dmu_dp->resize(ne, nv);
    dmu_dp->setFromTriplets(kept.begin(), kept.end());
  }
  if (counts) *counts = MapCounts{cut, band, frozen_pairs};
}

}  // namespace lsmbs
