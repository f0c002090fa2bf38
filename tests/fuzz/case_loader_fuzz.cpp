// Fuzz target for the case loader: any byte string is written to a case file and loaded by
// lsmbs::load_case(path), the command line's path (JSON parsing included), with the files of
// data/slider_crank/ (meshes, pressure table) beside it; design and optimization sections too.
// The loader may reject an input only with lsmbs::Error (exit code 2 in the command line), and
// the rejection must name the file and a JSON path (or, for a file that is no valid JSON
// document, the byte position or the parser's message); anything else —
// another exception, a crash, a hang, a sanitizer report, a message without a path — is a finding.
//
// Built two ways:
//   * with clang -fsanitize=fuzzer,address,undefined by scripts/fuzz.sh (libFuzzer drives it);
//   * as an ordinary executable `fuzz_replay` (LSMBS_FUZZ_REPLAY) that ctest runs over every
//     file of tests/fuzz/corpus/: the inputs found so far stay checked on every build, and the
//     seeds (seed_*.json, shipped cases) must load.
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "lsmbs/core/error.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/optimization_spec.hpp"

namespace {

namespace fs = std::filesystem;

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
      if (g.is_object() && g.contains("subgrid") && g["subgrid"].is_number() &&
          g["subgrid"].get<double>() > 32)
        return true;
  }
  return false;
}

// Largest bracket depth outside strings.
int nesting_depth(const std::string& text) {
  int depth = 0, worst = 0;
  bool in_string = false, escaped = false;
  for (char c : text) {
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      worst = std::max(worst, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return worst;
}

// A folder with links to the files of data/slider_crank/, where inputs are written and loaded.
const fs::path& work_dir() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() / ("lsmbs_fuzz_" + std::to_string(::getpid()));
    fs::create_directories(d);
    for (const auto& e :
         fs::directory_iterator(fs::path(LSMBS_SOURCE_DIR) / "data" / "slider_crank"))
      if (e.is_regular_file()) fs::create_symlink(e.path(), d / e.path().filename());
    return d;
  }();
  return dir;
}

enum class Outcome { kLoaded, kRejected, kRejectedWithoutPath, kSkipped };

// Loads the case file; returns how it ended (other exceptions propagate).
Outcome load(const fs::path& file) {
  {
    std::ifstream in(file, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (nesting_depth(text) <= 256) {  // deeper documents are the loader's to refuse (recursion)
      const auto j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
      if (!j.is_discarded() && too_large(j)) return Outcome::kSkipped;
    }
  }
  try {
    lsmbs::Case cs = lsmbs::load_case(file.string());
    if (cs.design && !cs.optimization.is_null()) lsmbs::parse_optimization(cs);
    return Outcome::kLoaded;
  } catch (const lsmbs::Error& e) {
    // "FILE: /json/path: …"; for a file that is no valid JSON document "FILE: byte N: …" (the
    // position in the file) or "FILE: invalid JSON: …"
    const std::string msg = e.what(), head = file.string() + ": ";
    const std::string rest = msg.rfind(head, 0) == 0 ? msg.substr(head.size()) : "";
    const bool named = rest.rfind("/", 0) == 0 || rest.rfind("byte ", 0) == 0 ||
                       rest.rfind("invalid JSON:", 0) == 0;
    if (!named) std::fprintf(stderr, "the rejection names no JSON path: %s\n", msg.c_str());
    return named ? Outcome::kRejected : Outcome::kRejectedWithoutPath;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const fs::path file = work_dir() / "input.json";
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  if (load(file) == Outcome::kRejectedWithoutPath) std::abort();  // a finding, like a crash
  return 0;
}

#ifdef LSMBS_FUZZ_REPLAY
#include <exception>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_replay CORPUS_DIR\n");
    return 2;
  }
  int n = 0, loaded = 0, rejected = 0, skipped = 0, failures = 0;
  for (const auto& e : fs::directory_iterator(argv[1])) {
    if (!e.is_regular_file()) continue;
    ++n;
    const std::string name = e.path().filename().string();
    const fs::path copy = work_dir() / name;  // beside the linked data files
    fs::copy_file(e.path(), copy, fs::copy_options::overwrite_existing);
    try {
      switch (load(copy)) {
        case Outcome::kLoaded:
          ++loaded;
          break;
        case Outcome::kSkipped:
          ++skipped;
          break;
        case Outcome::kRejectedWithoutPath:
          ++failures;
          std::fprintf(stderr, "FAIL: %s\n", name.c_str());
          break;
        case Outcome::kRejected:
          ++rejected;
          if (name.rfind("seed_", 0) == 0) {
            std::fprintf(stderr, "FAIL: seed %s is rejected (a shipped case must load)\n",
                         name.c_str());
            ++failures;
          }
          break;
      }
    } catch (const std::exception& x) {
      std::fprintf(stderr, "FAIL: %s: not an lsmbs::Error: %s\n", name.c_str(), x.what());
      ++failures;
    }
    fs::remove(copy);
  }
  fs::remove_all(work_dir());
  std::printf(
      "replayed %d inputs: %d loaded, %d rejected with a JSON path, %d skipped (too large), %d "
      "failures\n",
      n, loaded, rejected, skipped, failures);
  return n > 0 && failures == 0 ? 0 : 1;
}
#endif
