#pragma once
// JsonReader — typed, path-aware access to a JSON case file. Every accessor checks type and
// range and throws lsmbs::Error naming the file, the JSON path and what was expected; finish()
// rejects keys that were never read (typos such as "thickess" fail instead of being ignored).
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/core/types.hpp"

namespace lsmbs {

class JsonReader {
 public:
  JsonReader(const nlohmann::json& j, std::string file, std::string path = "")
      : j_(&j),
        file_(std::move(file)),
        path_(std::move(path)),
        used_(std::make_shared<std::set<std::string>>()) {}

  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  const nlohmann::json& raw() const { return *j_; }
  bool has(const std::string& key) const;
  bool is_object() const { return j_->is_object(); }
  bool is_array() const { return j_->is_array(); }
  bool is_string() const { return j_->is_string(); }
  size_t size() const { return j_->size(); }

  [[noreturn]] void fail(const std::string& what) const {
    throw Error(file_, path_.empty() ? "/" : path_, what);
  }
  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw Error(file_, path_ + "/" + key, what);
  }

  JsonReader child(const std::string& key) const;  ///< required
  std::optional<JsonReader> optional_child(const std::string& key) const;
  JsonReader at(size_t i) const;  ///< array element
  std::vector<JsonReader> items(const std::string& key, bool required = false) const;  ///< array of
  std::vector<std::string> keys() const;

  double number(const std::string& key) const;
  double number(const std::string& key, double def) const;
  double positive(const std::string& key) const;
  double positive(const std::string& key, double def) const;
  double non_negative(const std::string& key) const;
  double non_negative(const std::string& key, double def) const;
  int integer(const std::string& key, int min_value) const;
  int integer(const std::string& key, int def, int min_value) const;
  std::string string(const std::string& key) const;
  std::string string(const std::string& key, const std::string& def) const;
  std::string one_of(const std::string& key, const std::vector<std::string>& allowed,
                     const std::string& def = "") const;
  bool boolean(const std::string& key, bool def) const;
  Vec2 vec2(const std::string& key) const;
  Vec2 vec2(const std::string& key, const Vec2& def) const;
  Vec3 vec3(const std::string& key) const;
  Vec3 vec3(const std::string& key, const Vec3& def) const;
  /// This node itself as a number / string.
  double as_number() const;
  std::string as_string() const;

  /// Throws for keys of this object that no accessor read.
  void finish() const;

 private:
  std::string misspelt(const std::string& key) const;
  const nlohmann::json& get(const std::string& key) const;
  double checked_number(const nlohmann::json& v, const std::string& key) const;
  const nlohmann::json* j_;
  std::string file_, path_;
  std::shared_ptr<std::set<std::string>> used_;
};

}  // namespace lsmbs
