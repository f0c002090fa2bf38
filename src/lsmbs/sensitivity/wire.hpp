#pragma once
// Results as bytes, for the processes of one run (MPI ranks: runs/mpi.hpp) to hand each other
// what they computed. Every value is copied exactly (doubles bit for bit, NaN and infinities
// included); the bytes are read by the same build of lsmbs that wrote them, so the format has no
// version and no byte-order marks.
#include <string>
#include <vector>

#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {

std::string to_wire(const SensitivityResult& r);
SensitivityResult sensitivity_result_from_wire(const std::string& bytes);

std::string to_wire(const std::vector<ResponseSensitivity>& r);
std::vector<ResponseSensitivity> responses_from_wire(const std::string& bytes);

}  // namespace lsmbs
