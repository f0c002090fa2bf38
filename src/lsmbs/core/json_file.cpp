#include "lsmbs/core/json_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <set>
#include <vector>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/text.hpp"

namespace lsmbs {

namespace {

struct WrittenFiles {
  std::mutex mutex;
  std::vector<std::filesystem::path> paths;  // absolute, normalized
};
WrittenFiles& written_files() {
  static WrittenFiles w;
  return w;
}

}  // namespace

std::vector<std::string> files_written_under(const std::string& folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path root = fs::absolute(folder, ec).lexically_normal();
  std::vector<std::string> r;
  auto& w = written_files();
  std::lock_guard<std::mutex> lock(w.mutex);
  for (const auto& p : w.paths) {
    const fs::path rel = p.lexically_relative(root);
    if (!rel.empty() && *rel.begin() != ".." &&
        std::find(r.begin(), r.end(), rel.string()) == r.end())
      r.push_back(rel.string());
  }
  return r;
}

void write_file_atomic(const std::string& path, const std::string& content) {
  static std::atomic<unsigned> sequence{0};  // two threads writing one path never share a name
  const std::string tmp =
      path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(sequence.fetch_add(1));
  // POSIX calls rather than a stream: their errno names the reason (ENOSPC, EDQUOT, EIO), and the
  // temporary file is removed whatever fails, so a failed write leaves nothing behind
  auto fail = [&](const char* what, int err) {
    ::unlink(tmp.c_str());
    throw OutputError(path + ": " + what + ": " + std::strerror(err));
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int err = errno;
    throw OutputError(path + ": cannot create the file: " + std::strerror(err));
  }
  for (size_t done = 0; done < content.size();) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      ::close(fd);
      fail("cannot write the file", err);
    }
    done += static_cast<size_t>(n);
  }
  if (::close(fd) != 0) fail("cannot write the file", errno);
  if (::rename(tmp.c_str(), path.c_str()) != 0) fail("cannot put the file in place", errno);
  std::error_code ec;
  const auto abs = std::filesystem::absolute(path, ec).lexically_normal();
  auto& w = written_files();
  std::lock_guard<std::mutex> lock(w.mutex);
  w.paths.push_back(abs);
}

void write_json_atomic(const std::string& path, const nlohmann::json& j) {
  // strings are checked as UTF-8 where they come in (case files, options); U+FFFD for any that
  // is not rather than an exception after the run's work is done
  write_file_atomic(path, j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
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

namespace {

// A JSON pointer's reference token for an object key.
std::string pointer_token(const std::string& k) {
  std::string r;
  for (char c : k)
    r += c == '~' ? std::string("~0") : c == '/' ? std::string("~1") : std::string(1, c);
  return r;
}

// The JSON path of the string (a value, or a key of the object at the path) that holds `marker`,
// or nullopt.
std::optional<std::string> path_of(const nlohmann::json& j, const std::string& marker,
                                   const std::string& path, bool& key) {
  if (j.is_string()) {
    if (j.get_ref<const std::string&>().find(marker) == std::string::npos) return std::nullopt;
    key = false;
    return path;
  }
  if (j.is_object()) {
    for (const auto& [k, v] : j.items()) {
      if (k.find(marker) != std::string::npos) {
        key = true;
        return path;
      }
      if (auto p = path_of(v, marker, path + "/" + pointer_token(k), key)) return p;
    }
  }
  if (j.is_array())
    for (size_t i = 0; i < j.size(); ++i)
      if (auto p = path_of(j[i], marker, path + "/" + std::to_string(i), key)) return p;
  return std::nullopt;
}

// Text that is not UTF-8, named by the JSON path of the string that holds it. The parser's own
// message gives a byte, line and column, and echoes the broken bytes; the path says which name
// or value to fix. The first broken byte is replaced by a marker (U+10FFFE, a noncharacter no
// case uses), every later one by '?', the copy parsed, and the marker searched for.
void check_utf8(const std::string& text, const std::string& file) {
  const size_t bad = invalid_utf8_at(text);
  if (bad == std::string::npos) return;
  const std::string marker = "\xF4\x8F\xBF\xBE";
  std::string copy = text.substr(0, bad) + marker;
  for (size_t i = bad + 1; i < text.size();) {
    const size_t next = invalid_utf8_at(std::string_view(text).substr(i));
    if (next == std::string::npos) {
      copy.append(text, i, std::string::npos);
      break;
    }
    copy.append(text, i, next);
    copy += '?';
    i += next + 1;
  }
  char byte[8];
  std::snprintf(byte, sizeof byte, "0x%02X", static_cast<unsigned char>(text[bad]));
  const std::string what = std::string("not valid UTF-8 (byte ") + std::to_string(bad + 1) + ", " +
                           byte + "): JSON text is UTF-8; save the case file as UTF-8";
  std::optional<std::string> path;
  bool key = false;
  try {
    path = path_of(nlohmann::json::parse(copy), marker, "", key);
  } catch (const nlohmann::json::exception&) {  // not in a string: the parser's message says where
  }
  if (!path)
    throw Error(
        file, "byte " + std::to_string(bad + 1),
        std::string("invalid JSON: a byte that is not UTF-8 (") + byte + "), outside any string");
  throw Error(file, path->empty() ? "/" : *path,
              (key ? "a key of this object is " : "the string is ") + what);
}

}  // namespace

nlohmann::json parse_json_document(const std::string& text, const std::string& file) {
  check_json_depth(text, file);
  check_utf8(text, file);
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
