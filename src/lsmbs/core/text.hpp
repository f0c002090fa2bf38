#pragma once
// User strings (names from case files, Python and the command line) are data wherever they meet
// another format: these are the checks and the conversions every writer uses.
#include <cstddef>
#include <string>

namespace lsmbs {

/// True when `s` is valid UTF-8 (no overlong forms, surrogates or code points past U+10FFFF).
bool valid_utf8(const std::string& s);

/// `s` as text to show (in a picture, an XML attribute): invalid UTF-8 and control characters
/// (C0, DEL, C1) become U+FFFD, and text longer than `max_chars` code
/// points is cut with an ellipsis.
std::string displayable_text(const std::string& s, size_t max_chars = 200);

/// A name as a file-name stem: ASCII letters and digits, '-', '_' and '.' are kept, every other
/// byte becomes '_'; a leading '.' becomes '_' (no hidden files, never "." or ".."); at most 64
/// bytes; "" becomes "_". Distinct names can share a stem: callers that name several files make
/// the stems unique (io/output.hpp, body_file_stems).
std::string file_stem(const std::string& name);

}  // namespace lsmbs
