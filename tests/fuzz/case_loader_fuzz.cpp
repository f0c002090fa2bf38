// Fuzz target for the case loader: any byte string is parsed as JSON and loaded as a case
// (every section, meshes from the shipped data folder, design and optimization sections).
// The loader may reject an input only with lsmbs::Error (exit code 2 in the command line);
// anything else — another exception, a crash, a hang, a sanitizer report — is a finding.
//
// Built two ways:
//   * with clang -fsanitize=fuzzer,address,undefined by scripts/fuzz.sh (libFuzzer drives it);
//   * as an ordinary executable `fuzz_replay` (LSMBS_FUZZ_REPLAY) that ctest runs over every
//     file of tests/fuzz/corpus/ — the inputs found so far stay checked on every build.
#include <cstddef>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "lsmbs/core/error.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/optimization_spec.hpp"

namespace {

// Inputs whose meshes would take more than the fuzzer's memory and time budget are skipped
// (a real case may be that large; it is not a loader bug). Counts elements of rectangle meshes.
bool too_large(const nlohmann::json& j) {
  if (!j.is_object() || !j.contains("bodies") || !j["bodies"].is_array()) return false;
  for (const auto& b : j["bodies"]) {
    if (!b.is_object() || !b.contains("mesh") || !b["mesh"].is_object()) continue;
    const auto& m = b["mesh"];
    if (m.contains("elements") && m["elements"].is_array() && m["elements"].size() == 2 &&
        m["elements"][0].is_number() && m["elements"][1].is_number()) {
      const double n = m["elements"][0].get<double>() * m["elements"][1].get<double>();
      if (n > 2e4) return true;
    }
    if (m.contains("subgrid")) return true;
  }
  if (j.contains("design") && j["design"].is_object()) {
    for (const auto& g : j["design"].value("geometry", nlohmann::json::array()))
      if (g.is_object() && g.contains("subgrid") && g["subgrid"].is_number() && g["subgrid"].get<double>() > 32) return true;
  }
  return false;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(data, data + size);
  } catch (const nlohmann::json::exception&) {
    // not JSON, or a number out of range (1e999): load_case reports both as invalid JSON with
    // exit code 2 — this finding of the fuzzer used to end in an "internal error"
    return 0;
  }
  if (too_large(j)) return 0;
  try {
    lsmbs::Case cs = lsmbs::load_case_json(j, "<fuzz>", LSMBS_SOURCE_DIR "/data/slider_crank");
    if (cs.design && !cs.optimization.is_null()) lsmbs::parse_optimization(cs);
  } catch (const lsmbs::Error&) {
    // a clear rejection: the intended outcome for bad input
  }
  return 0;
}

#ifdef LSMBS_FUZZ_REPLAY
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_replay CORPUS_DIR\n");
    return 2;
  }
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(argv[1])) {
    if (!e.is_regular_file()) continue;
    std::ifstream f(e.path(), std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
    ++n;
  }
  std::printf("replayed %d inputs without a crash\n", n);
  return n > 0 ? 0 : 1;
}
#endif
