#include "lsmbs/mbs/parameterization.hpp"

#include <map>
#include <stdexcept>
#include <utility>

namespace lsmbs {

DirectionalParameterization::DirectionalParameterization(const Parameterization& base, Vec p0,
                                                         Mat W)
    : base_(base), p0_(std::move(p0)), W_(std::move(W)) {
  if (p0_.size() != base.size() || W_.rows() != base.size())
    throw std::invalid_argument(
        "DirectionalParameterization: p0 and W must have a row per variable");
}

void DirectionalParameterization::apply(const Vec& s, ModelParams& params) const {
  base_.apply(p0_ + W_ * s, params);
}

std::vector<ParamDirection> DirectionalParameterization::apply_with_directions(
    const Vec& s, ModelParams& params) const {
  const auto dirs = base_.apply_with_directions(p0_ + W_ * s, params);
  std::vector<ParamDirection> out(static_cast<size_t>(W_.cols()));
  for (Eigen::Index j = 0; j < W_.cols(); ++j) {
    std::map<std::pair<int, int>, double> fields;
    std::map<int, double> scalars;
    for (size_t i = 0; i < dirs.size(); ++i) {
      const double w = W_(static_cast<Eigen::Index>(i), j);
      if (w == 0) continue;
      for (const auto& f : dirs[i].fields) fields[{f.field, f.element}] += w * f.value;
      for (const auto& [k, v] : dirs[i].scalars) scalars[k] += w * v;
    }
    auto& d = out[static_cast<size_t>(j)];
    for (const auto& [key, v] : fields) d.fields.push_back({key.first, key.second, v});
    for (const auto& [k, v] : scalars) d.scalars.emplace_back(k, v);
  }
  return out;
}

}  // namespace lsmbs
