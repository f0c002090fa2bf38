#pragma once
// JSON records of the numerical options, counts and results, as summary.json and the optimizer's
// checkpoint write them. The numerical headers know nothing of JSON; these are nlohmann's
// `to_json` hooks (found by argument-dependent lookup), so `nlohmann::json j = options;` works.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/integrators/idas_ggl.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {

void to_json(nlohmann::json& j, const GeneralizedAlphaOptions& o);
void to_json(nlohmann::json& j, const IntegratorSummary& s);
void to_json(nlohmann::json& j, const IdasOptions& o);
void to_json(nlohmann::json& j, const IdasStats& s);
void to_json(nlohmann::json& j, const SensitivityOptions& o);
void to_json(nlohmann::json& j, const SensitivityCounts& c);
void to_json(nlohmann::json& j, const GradientCheckOptions& o);
/// The check's options, direction, per-response disagreement and verdict.
nlohmann::json gradient_check_json(const GradientCheckResult& r, const GradientCheckOptions& o);
/// IDAS quadrature responses by name: value, definition, window [a, b], gradient by variable name.
nlohmann::json quadratures_json(const std::vector<QuadratureResponse>& r,
                                const std::vector<std::string>& variables);

}  // namespace lsmbs
