#include "lsmbs/sensitivity/study.hpp"

#include "lsmbs/core/error.hpp"

namespace lsmbs {

Study::Study(ModelBuilder& builder, GeneralizedAlphaOptions o)
    : model(builder.build()),
      initial(builder.initial_state()),
      simulation(std::move(o)),
      start(builder.start()) {}

std::vector<std::string> Study::measure_columns() const {
  std::vector<std::string> c;
  for (const auto& m : measures)
    for (auto& s : m->components()) c.push_back(s);
  return c;
}

std::vector<std::string> Study::measure_units() const {
  std::vector<std::string> u;
  for (const auto& m : measures)
    for (auto& s : m->units()) u.push_back(s);
  return u;
}

std::string Study::response_unit(size_t r) const {
  const auto& spec = responses.at(r);
  return ResponseSpec::unit(spec.kind, measure_units().at(static_cast<size_t>(spec.column)));
}

Measure& Study::add_measure(std::unique_ptr<Measure> m) {
  for (const auto& c : m->components())
    if (measure_column(c) >= 0)
      throw SetupError("measures", "measure column '" + c + "' exists already");
  measures.push_back(std::move(m));
  return *measures.back();
}

ResponseSpec& Study::add_response(const std::string& name, const std::string& measure,
                                  ResponseSpec::Kind kind, double t0, double t1) {
  if (response_index(name) >= 0)
    throw SetupError("responses", "response '" + name + "' exists already");
  ResponseSpec r;
  r.name = name;
  r.column = measure_column(measure);
  if (r.column < 0)
    throw SetupError("responses",
                     "response '" + name + "': unknown measure column '" + measure + "'");
  r.kind = kind;
  r.t0 = t0;
  r.t1 = t1;
  r.window_text = t0 > -1e299 || t1 < 1e299
                      ? "[" + std::to_string(t0) + ", " + std::to_string(t1) + "] s"
                      : "whole run";
  responses.push_back(r);
  return responses.back();
}

void Study::set_design(std::unique_ptr<Design> d) {
  design = std::move(d);
  if (design) design->apply(design->initial(), model->params());
}

int Study::measure_column(const std::string& name) const {
  const auto c = measure_columns();
  for (size_t i = 0; i < c.size(); ++i)
    if (c[i] == name) return static_cast<int>(i);
  return -1;
}

int Study::response_index(const std::string& name) const {
  for (size_t i = 0; i < responses.size(); ++i)
    if (responses[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace lsmbs
