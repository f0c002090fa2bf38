#pragma once
// User text (names from case files, Python and the command line; fields of table and mesh files)
// is data wherever it meets another format:
//  * strict reading of numbers: a field is a number only if all of it is (a prefix parser such as
//    istream >>, strtod or stod reads "1.2x", "1.2rad" or a number cut short by a NUL byte as 1.2
//    without a word, so every reader of user text parses whole fields with these);
//  * safe display in messages (shown), in pictures and XML attributes (displayable_text), and in
//    file names (file_stem).
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace lsmbs {

/// The finite double that the whole of `s` spells (decimal or exponent form, optional sign);
/// nullopt for anything else: empty, other characters before or after, inf, nan, hexadecimal,
/// beyond double range (1e999) or below it (1e-400).
std::optional<double> parse_finite_double(std::string_view s);

/// The integer that the whole of `s` spells (decimal digits with an optional sign); nullopt
/// for anything else or beyond the range of long long.
std::optional<long long> parse_integer(std::string_view s);

/// What a message shows of user text: `s` in single quotes, printable ASCII as is and every
/// other byte as \xNN (a NUL, a line break or a byte of broken UTF-8 stays visible and cannot
/// reach the terminal or another program), cut after `max` bytes with "...".
std::string shown(std::string_view s, size_t max = 60);

/// The fields of a line separated by runs of spaces and tabs (none for a blank line).
std::vector<std::string_view> whitespace_fields(std::string_view line);

/// `message` with every whole-word occurrence of a name in `names` (first) replaced by its
/// spelling in the caller's interface (second): an options struct's validate() message names its
/// fields ("fail: expected ... >= warn"); the command line prints its flags instead
/// ("--check-fail: expected ... >= --check-warn") and Python its keywords.
std::string rename_fields(const std::string& message,
                          const std::vector<std::pair<std::string, std::string>>& names);

/// Byte offset of the first byte of `s` that is not part of well-formed UTF-8 (overlong forms,
/// surrogates and code points beyond U+10FFFF included), or std::string_view::npos.
size_t invalid_utf8_at(std::string_view s);
/// True when `s` is well-formed UTF-8 (invalid_utf8_at finds nothing).
inline bool valid_utf8(std::string_view s) { return invalid_utf8_at(s) == std::string_view::npos; }

/// `s` as text to show (in a picture, an XML attribute): invalid UTF-8 and control characters
/// (C0, DEL, C1) become U+FFFD, and text longer than `max_chars` code points is cut with an
/// ellipsis.
std::string displayable_text(const std::string& s, size_t max_chars = 200);

/// A name as a file-name stem: ASCII letters and digits, '-', '_' and '.' are kept, every other
/// byte becomes '_'; a leading '.' becomes '_' (no hidden files, never "." or ".."); at most 64
/// bytes; "" becomes "_". Distinct names can share a stem: callers that name several files make
/// the stems unique (io/output.hpp, body_file_stems).
std::string file_stem(const std::string& name);

}  // namespace lsmbs
