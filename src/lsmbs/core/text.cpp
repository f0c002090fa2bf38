#include "lsmbs/core/text.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace lsmbs {

std::optional<double> parse_finite_double(std::string_view s) {
  // from_chars takes no '+' (CSV writers and Gmsh may write one): skip it, but not "+-1"
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  double v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v))
    return std::nullopt;
  return v;
}

std::optional<long long> parse_integer(std::string_view s) {
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  long long v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, 10);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::string shown(std::string_view s, size_t max) {
  std::string r = "'";
  for (size_t i = 0; i < s.size() && i < max; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      r += static_cast<char>(c);
    } else {
      char b[8];
      std::snprintf(b, sizeof b, "\\x%02x", c);
      r += b;
    }
  }
  if (s.size() > max) r += "...";
  return r + "'";
}

std::vector<std::string_view> whitespace_fields(std::string_view line) {
  std::vector<std::string_view> f;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > b) f.push_back(line.substr(b, i - b));
  }
  return f;
}

std::string rename_fields(const std::string& message,
                          const std::vector<std::pair<std::string, std::string>>& names) {
  auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  std::string out;
  for (size_t i = 0; i < message.size();) {
    bool replaced = false;
    if (i == 0 || !word(message[i - 1]))
      for (const auto& [from, to] : names) {
        const size_t e = i + from.size();
        if (!from.empty() && message.compare(i, from.size(), from) == 0 &&
            (e == message.size() || !word(message[e]))) {
          out += to;
          i = e;
          replaced = true;
          break;
        }
      }
    if (!replaced) out += message[i++];
  }
  return out;
}

size_t invalid_utf8_at(std::string_view s) {
  const auto* u = reinterpret_cast<const unsigned char*>(s.data());
  const size_t n = s.size();
  for (size_t i = 0; i < n;) {
    const unsigned c = u[i];
    if (c < 0x80) {
      ++i;
      continue;
    }
    // the lead byte gives the length and the range of the second byte (RFC 3629, table 3-7 of
    // the Unicode standard): no overlong forms, no surrogates, nothing beyond U+10FFFF
    size_t len = 0;
    unsigned lo = 0x80, hi = 0xbf;
    if (c >= 0xc2 && c <= 0xdf) {
      len = 2;
    } else if (c >= 0xe0 && c <= 0xef) {
      len = 3;
      if (c == 0xe0) lo = 0xa0;
      if (c == 0xed) hi = 0x9f;
    } else if (c >= 0xf0 && c <= 0xf4) {
      len = 4;
      if (c == 0xf0) lo = 0x90;
      if (c == 0xf4) hi = 0x8f;
    } else {
      return i;
    }
    if (i + len > n) return i;
    if (u[i + 1] < lo || u[i + 1] > hi) return i;
    for (size_t k = 2; k < len; ++k)
      if (u[i + k] < 0x80 || u[i + k] > 0xbf) return i;
    i += len;
  }
  return std::string_view::npos;
}

}  // namespace lsmbs
