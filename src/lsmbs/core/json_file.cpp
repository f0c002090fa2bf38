#include "lsmbs/core/json_file.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <vector>

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

nlohmann::json parse_json_document(const std::string& text, const std::string& file) {
  check_json_depth(text, file);
  struct Frame {
    bool object;
    std::set<std::string> keys;
    std::string key;  // objects: the member being parsed
    long index = 0;   // arrays: the element being parsed
  };
  std::vector<Frame> open;
  auto escaped = [](const std::string& k) {  // a JSON pointer's reference token
    std::string r;
    for (char c : k)
      r += c == '~' ? std::string("~0") : c == '/' ? std::string("~1") : std::string(1, c);
    return r;
  };
  auto path = [&] {
    std::string p;
    for (const Frame& f : open) p += "/" + (f.object ? escaped(f.key) : std::to_string(f.index));
    return p;
  };
  using E = nlohmann::json::parse_event_t;
  return nlohmann::json::parse(text, [&](int, E event, nlohmann::json& parsed) {
    switch (event) {
      case E::object_start:
      case E::array_start:
        open.push_back({event == E::object_start, {}, {}, 0});
        break;
      case E::key: {
        Frame& f = open.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second)
          throw Error(file, path(),
                      "the key '" + f.key +
                          "' appears twice in this object (JSON keeps only one of them silently); "
                          "remove one");
        break;
      }
      case E::object_end:
      case E::array_end:
        open.pop_back();
        if (!open.empty() && !open.back().object) ++open.back().index;
        break;
      case E::value:
        if (!open.empty() && !open.back().object) ++open.back().index;
        break;
    }
    return true;
  });
}

}  // namespace lsmbs
