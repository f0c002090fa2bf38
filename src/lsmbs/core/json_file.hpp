#pragma once
// Files every layer writes or reads safely: atomic writes (a temporary file in the same folder,
// then rename, so an interrupted run never leaves a half-written file that looks complete) and a
// nesting-depth check before JSON parsing.
#include <nlohmann/json.hpp>
#include <string>

namespace lsmbs {

void write_file_atomic(const std::string& path, const std::string& content);
void write_json_atomic(const std::string& path, const nlohmann::json& j);

/// Throws lsmbs::Error (file, byte offset) when `text` nests arrays or objects deeper than
/// `max_depth`: nlohmann::json parses recursively, and 200,000 levels exhaust the stack.
void check_json_depth(const std::string& text, const std::string& file, int max_depth = 256);

/// Parses a case document: the depth check above, then nlohmann::json with every object's keys
/// checked for duplicates, which JSON parsers otherwise resolve silently (the last one wins).
/// Throws lsmbs::Error (file, JSON path of the repeated key) on a duplicate, and (file, JSON path
/// of the string) on text that is not UTF-8; nlohmann's own exceptions on other invalid JSON.
nlohmann::json parse_json_document(const std::string& text, const std::string& file);

}  // namespace lsmbs
