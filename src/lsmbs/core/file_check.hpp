#pragma once
// Why a path named in a case (case file, mesh, table) cannot be read as a file, in words a user
// can act on: it does not exist, it is a folder, it is a device or pipe (reading one could block
// or never end), or it cannot be opened (permissions). Empty when the file can be read.
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace lsmbs {

inline std::string unreadable_file_reason(const std::string& path) {
  namespace fs = std::filesystem;
  if (path.empty()) return "empty file name";
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) return "no such file";
  if (fs::is_directory(st)) return "is a folder, not a file";
  if (!fs::is_regular_file(st)) return "is not a regular file (a device, pipe or socket)";
  std::ifstream f(path, std::ios::binary);
  if (!f) return std::string("cannot be read (") + std::strerror(errno) + ")";
  return {};
}

}  // namespace lsmbs
