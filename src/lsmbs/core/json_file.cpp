#include "lsmbs/core/json_file.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "lsmbs/core/error.hpp"

namespace lsmbs {

void write_file_atomic(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) throw Error(path, "", "cannot write output file");
    f << content;
    f.flush();
    if (!f) throw Error(path, "", "error while writing output file");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw Error(path, "", "cannot rename temporary output file: " + ec.message());
}

void write_json_atomic(const std::string& path, const nlohmann::json& j) {
  write_file_atomic(path, j.dump(2) + "\n");
}

void check_json_depth(const std::string& text, const std::string& file, int max_depth) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char ch = text[i];
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (ch == '\\')
        escaped = true;
      else if (ch == '"')
        in_string = false;
    } else if (ch == '"') {
      in_string = true;
    } else if (ch == '[' || ch == '{') {
      if (++depth > max_depth)
        throw Error(file, "byte " + std::to_string(i),
                    "invalid JSON: nested deeper than " + std::to_string(max_depth) + " levels");
    } else if (ch == ']' || ch == '}') {
      --depth;
    }
  }
}

}  // namespace lsmbs
