#pragma once
// SHA-256 (FIPS 180-4) of a byte string, as lowercase hex: the case-file hash in summary.json.
#include <string>
#include <string_view>

namespace lsmbs {
std::string sha256_hex(std::string_view data);
}
