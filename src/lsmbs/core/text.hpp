#pragma once
// Strict reading of numbers from user text (table and mesh files, command-line values) and safe
// display of user text in messages. A field is a number only if all of it is: a prefix parser
// (istream >>, strtod, stod) reads "1.2x", "1.2rad" or a number cut short by a NUL byte as 1.2
// without a word, so every reader of user text parses whole fields with these.
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

}  // namespace lsmbs
