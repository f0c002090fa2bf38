#pragma once
// lsmbs::Error — invalid input or usage (exit code 2). The message names the file, the JSON
// path and what was expected, e.g.  "robot.json: /bodies/2/thickness: expected a positive
// number, got -0.001".  Numerical failures are not Errors: they are reported as Status.
#include <stdexcept>
#include <string>

namespace lsmbs {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
  Error(const std::string& file, const std::string& json_path, const std::string& what)
      : std::runtime_error(format(file, json_path, what)), file_(file), path_(json_path) {}

  const std::string& file() const { return file_; }
  const std::string& json_path() const { return path_; }

 private:
  static std::string format(const std::string& file, const std::string& path,
                            const std::string& what) {
    std::string out;
    if (!file.empty()) out += file + ": ";
    if (!path.empty()) out += path + ": ";
    return out + what;
  }
  std::string file_, path_;
};

/// Invalid use of the library, named by what is wrong rather than by where it came from: the
/// `subject` is a name such as "design", "responses", "optimization.objective" or
/// "simulation.newton". The library below io/ knows no files; the JSON front end maps the subject
/// to the case file and its JSON path (io/case.hpp, `locate`).
class SetupError : public Error {
 public:
  SetupError(const std::string& subject, const std::string& what)
      : Error(subject + ": " + what), subject_(subject), what_(what) {}
  const std::string& subject() const { return subject_; }
  const std::string& reason() const { return what_; }

 private:
  std::string subject_, what_;
};

/// A numerical failure (Newton divergence, singular matrix, NaN): exit code 1.
class NumericalFailure : public std::runtime_error {
 public:
  explicit NumericalFailure(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace lsmbs
