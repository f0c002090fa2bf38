#pragma once
// Status — outcome of a numerical operation the caller may recover from (retry with a
// smaller step, report). Input errors throw lsmbs::Error instead.
#include <string>

namespace lsmbs {

struct Status {
  enum class Code { kOk, kNotConverged, kSingular, kNonFinite };
  Code code = Code::kOk;
  std::string message;

  bool ok() const { return code == Code::kOk; }
  static Status Ok() { return {}; }
  static Status Fail(Code c, std::string msg) { return {c, std::move(msg)}; }
};

}  // namespace lsmbs
