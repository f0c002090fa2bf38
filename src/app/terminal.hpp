#pragma once
// What the command line prints is text a terminal interprets: a name from a case file that holds
// escape sequences would retitle the window, recolour it or rewrite lines above (a response named
// "\x1b]0;…\x07"). filter_control_characters() puts a filter on stdout and stderr that prints
// every C0 control character but line feed, tab and carriage return, DEL and the C1 controls
// (U+0080–U+009F) as visible escapes (\x1b, \u009b). The progress line's own control sequence is
// written past the filter (raw_control).
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

namespace lsmbs::app {

namespace detail {

struct FilteredStream {
  int fd;
  bool lead_c2 = false;  // the last byte was 0xC2, the lead byte of a C1 control in UTF-8
};

inline void write_all(int fd, const char* p, size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return;  // the stream is gone (a closed pipe): nothing more to do
    p += w;
    n -= static_cast<size_t>(w);
  }
}

inline ssize_t filtered_write(void* cookie, const char* buf, size_t n) {
  auto& f = *static_cast<FilteredStream*>(cookie);
  std::string out;
  out.reserve(n + 16);
  char esc[8];
  for (size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(buf[i]);
    if (f.lead_c2) {
      f.lead_c2 = false;
      if (c >= 0x80 && c <= 0x9f) {
        std::snprintf(esc, sizeof esc, "\\u%04x", c);
        out += esc;
        continue;
      }
      out += '\xc2';
    }
    if (c == 0xc2) {
      f.lead_c2 = true;
      continue;
    }
    if ((c < 0x20 && c != '\n' && c != '\t' && c != '\r') || c == 0x7f) {
      std::snprintf(esc, sizeof esc, "\\x%02x", c);
      out += esc;
      continue;
    }
    out += static_cast<char>(c);
  }
  write_all(f.fd, out.data(), out.size());
  return static_cast<ssize_t>(n);
}

inline int filtered_close(void* cookie) {
  auto& f = *static_cast<FilteredStream*>(cookie);
  if (f.lead_c2) write_all(f.fd, "\xc2", 1);
  f.lead_c2 = false;
  return 0;
}

inline FILE* filtered(FILE* stream, int fd, int mode) {
  static FilteredStream cookies[2] = {{STDOUT_FILENO}, {STDERR_FILENO}};
  cookie_io_functions_t io{};
  io.write = filtered_write;
  io.close = filtered_close;
  std::fflush(stream);
  FILE* f = fopencookie(&cookies[fd == STDERR_FILENO ? 1 : 0], "w", io);
  if (!f) return stream;  // keep the plain stream rather than none
  std::setvbuf(f, nullptr, mode, mode == _IONBF ? 0 : BUFSIZ);
  return f;
}

}  // namespace detail

/// Filters stdout (line-buffered on a terminal, else fully buffered) and stderr (unbuffered).
inline void filter_control_characters() {
  stdout = detail::filtered(stdout, STDOUT_FILENO, ::isatty(STDOUT_FILENO) ? _IOLBF : _IOFBF);
  stderr = detail::filtered(stderr, STDERR_FILENO, _IONBF);
}

/// A control sequence of the program's own on stderr, past the filter, after what is pending.
inline void raw_control(const char* s) {
  std::fflush(stderr);
  detail::write_all(STDERR_FILENO, s, std::strlen(s));
}

}  // namespace lsmbs::app
