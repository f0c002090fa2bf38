#include "lsmbs/io/json_reader.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace lsmbs {
namespace {
std::string type_name(const nlohmann::json& v) { return v.type_name(); }
std::string shown(const nlohmann::json& v) {
  std::string s = v.dump();
  return s.size() > 60 ? s.substr(0, 57) + "..." : s;
}
// "string \"abc\"", "boolean true", "null" (a null shows once)
std::string described(const nlohmann::json& v) {
  return v.is_null() ? type_name(v) : type_name(v) + " " + shown(v);
}

// Levenshtein distance, for "did you mean"
size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}
}  // namespace

// " (the entry has 'axes': a misspelling?)" when a key of the object is within two edits of the
// missing one and is not a key the reader has used.
std::string JsonReader::misspelt(const std::string& key) const {
  for (auto it = j_->begin(); it != j_->end(); ++it)
    if (!used_->count(it.key()) &&
        edit_distance(it.key(), key) <= std::min<size_t>(2, key.size() / 3))
      return " (the entry has '" + it.key() + "': a misspelling of it?)";
  return "";
}

bool JsonReader::has(const std::string& key) const { return j_->is_object() && j_->contains(key); }

const nlohmann::json& JsonReader::get(const std::string& key) const {
  if (!j_->is_object()) fail("expected an object, got " + type_name(*j_));
  if (!j_->contains(key)) fail("missing required key '" + key + "'" + misspelt(key));
  used_->insert(key);
  return (*j_)[key];
}

JsonReader JsonReader::child(const std::string& key) const {
  return JsonReader(get(key), file_, path_ + "/" + key);
}

std::optional<JsonReader> JsonReader::optional_child(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  return child(key);
}

JsonReader JsonReader::at(size_t i) const {
  if (!j_->is_array()) fail("expected an array, got " + type_name(*j_));
  return JsonReader((*j_)[i], file_, path_ + "/" + std::to_string(i));
}

std::vector<JsonReader> JsonReader::items(const std::string& key, bool required) const {
  std::vector<JsonReader> r;
  if (!has(key)) {
    if (required) get(key);
    return r;
  }
  JsonReader c = child(key);
  if (!c.is_array()) c.fail("expected an array, got " + type_name(c.raw()));
  for (size_t i = 0; i < c.size(); ++i) r.push_back(c.at(i));
  return r;
}

std::vector<std::string> JsonReader::keys() const {
  std::vector<std::string> k;
  if (j_->is_object())
    for (auto it = j_->begin(); it != j_->end(); ++it) k.push_back(it.key());
  return k;
}

double JsonReader::checked_number(const nlohmann::json& v, const std::string& key) const {
  if (!v.is_number()) fail(key, "expected a number, got " + described(v));
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(key, "expected a finite number");
  return d;
}

double JsonReader::number(const std::string& key) const { return checked_number(get(key), key); }
double JsonReader::number(const std::string& key, double def) const {
  return has(key) ? number(key) : def;
}

double JsonReader::positive(const std::string& key) const {
  const double d = number(key);
  if (!(d > 0)) fail(key, "expected a positive number, got " + shown((*j_)[key]));
  return d;
}
double JsonReader::positive(const std::string& key, double def) const {
  return has(key) ? positive(key) : def;
}

double JsonReader::non_negative(const std::string& key) const {
  const double d = number(key);
  if (!(d >= 0)) fail(key, "expected a non-negative number, got " + shown((*j_)[key]));
  return d;
}
double JsonReader::non_negative(const std::string& key, double def) const {
  return has(key) ? non_negative(key) : def;
}

int JsonReader::integer(const std::string& key, int min_value) const {
  const auto& v = get(key);
  if (!v.is_number_integer()) fail(key, "expected an integer, got " + described(v));
  const long long i = v.get<long long>();
  if (i < min_value || i > 100000000)
    fail(key, "expected an integer >= " + std::to_string(min_value) + ", got " + shown(v));
  return static_cast<int>(i);
}
int JsonReader::integer(const std::string& key, int def, int min_value) const {
  return has(key) ? integer(key, min_value) : def;
}

std::string JsonReader::string(const std::string& key) const {
  const auto& v = get(key);
  if (!v.is_string()) fail(key, "expected a string, got " + described(v));
  const auto s = v.get<std::string>();
  if (s.empty()) fail(key, "expected a non-empty string");
  return s;
}
std::string JsonReader::string(const std::string& key, const std::string& def) const {
  return has(key) ? string(key) : def;
}

std::string JsonReader::one_of(const std::string& key, const std::vector<std::string>& allowed,
                               const std::string& def) const {
  if (!has(key) && !def.empty()) return def;
  const std::string s = string(key);
  for (const auto& a : allowed)
    if (a == s) return s;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + ("\"" + a + "\"");
  fail(key, "expected one of " + list + ", got \"" + s + "\"");
}

bool JsonReader::boolean(const std::string& key, bool def) const {
  if (!has(key)) return def;
  const auto& v = get(key);
  if (!v.is_boolean()) fail(key, "expected true or false, got " + type_name(v));
  return v.get<bool>();
}

Vec2 JsonReader::vec2(const std::string& key) const {
  const auto& v = get(key);
  if (!v.is_array() || v.size() != 2)
    fail(key, "expected an array of two numbers [x, y], got " + shown(v));
  return Vec2(checked_number(v[0], key + "/0"), checked_number(v[1], key + "/1"));
}
Vec2 JsonReader::vec2(const std::string& key, const Vec2& def) const {
  return has(key) ? vec2(key) : def;
}

Vec3 JsonReader::vec3(const std::string& key) const {
  const auto& v = get(key);
  if (!v.is_array() || v.size() != 3)
    fail(key, "expected an array of three numbers [x, y, z], got " + shown(v));
  return Vec3(checked_number(v[0], key + "/0"), checked_number(v[1], key + "/1"),
              checked_number(v[2], key + "/2"));
}
Vec3 JsonReader::vec3(const std::string& key, const Vec3& def) const {
  return has(key) ? vec3(key) : def;
}

double JsonReader::as_number() const {
  if (!j_->is_number()) fail("expected a number, got " + type_name(*j_));
  const double d = j_->get<double>();
  if (!std::isfinite(d)) fail("expected a finite number");
  return d;
}

std::string JsonReader::as_string() const {
  if (!j_->is_string()) fail("expected a string, got " + type_name(*j_));
  return j_->get<std::string>();
}

void JsonReader::finish() const {
  if (!j_->is_object()) return;
  for (auto it = j_->begin(); it != j_->end(); ++it)
    if (!used_->count(it.key()) && it.key().rfind("_", 0) != 0 && it.key() != "comment" &&
        it.key() != "description")
      fail(it.key(), "unknown key (check the spelling; see docs/case-format.md)");
}

}  // namespace lsmbs
