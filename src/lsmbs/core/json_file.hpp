#pragma once
// Files every layer writes or reads safely: atomic writes (a temporary file in the same folder,
// then rename, so an interrupted run never leaves a half-written file that looks complete) and a
// nesting-depth check before JSON parsing.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace lsmbs {

/// Writes `content` to `path` through a temporary file and a rename. Throws OutputError (the file,
/// the system's reason) when the file cannot be written; no temporary file is left then.
void write_file_atomic(const std::string& path, const std::string& content);
/// The files write_file_atomic has put in place in this process below `folder` (relative paths,
/// in the order first written): what a run that fails lists in its summary.json.
std::vector<std::string> files_written_under(const std::string& folder);
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
