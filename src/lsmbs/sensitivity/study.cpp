#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

std::vector<std::string> Study::measure_columns() const {
  std::vector<std::string> c;
  for (const auto& m : measures)
    for (auto& s : m->components()) c.push_back(s);
  return c;
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
