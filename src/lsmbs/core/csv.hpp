#pragma once
// CSV fields that every reader takes as they are meant (RFC 4180): names quoted where needed, and
// numbers written so that they read back as the same doubles.
#include <string>

namespace lsmbs {

/// One CSV field: `s` as is, or in double quotes (inner quotes doubled) when it holds a comma, a
/// quote, a line break or a leading or trailing space.
std::string csv_field(const std::string& s);
/// A double as the shortest of "%.15g", "%.16g", "%.17g" that reads back as the same double
/// ("%.17g" always does); "nan", "inf" and "-inf" for the non-finite ones.
std::string csv_number(double v);

}  // namespace lsmbs
