#pragma once
// lsmbs::Error — invalid input or usage (exit code 2). The message names the file, the JSON
// path and what was expected, e.g.  "robot.json: /bodies/2/thickness: expected a positive
// number, got -0.001".  Numerical failures are not Errors: they are reported as Status.
#include <stdexcept>
#include <string>
#include <utility>

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
/// "simulation.newton"; a check of one entity of the model (a body, joint or force, by its name)
/// also names the `entity` and, optionally, its `field` ("velocity"). The library below io/ knows
/// no files; the JSON front end maps the subject, or the entity, to the case file and its JSON
/// path (io/case.hpp, `locate`).
class SetupError : public Error {
 public:
  SetupError(const std::string& subject, const std::string& what, std::string entity = {},
             std::string field = {})
      : Error(format(subject, entity, field) + ": " + what),
        subject_(subject),
        what_(what),
        entity_(std::move(entity)),
        field_(std::move(field)) {}
  const std::string& subject() const { return subject_; }
  const std::string& reason() const { return what_; }
  const std::string& entity() const { return entity_; }  ///< a body, joint or force; or empty
  const std::string& field() const { return field_; }    ///< of the entity's entry; or empty

 private:
  static std::string format(const std::string& subject, const std::string& entity,
                            const std::string& field) {
    if (entity.empty()) return subject;
    return subject + " '" + entity + "'" + (field.empty() ? "" : "/" + field);
  }
  std::string subject_, what_, entity_, field_;
};

/// An invalid model built in code (mbs/model_builder.hpp): it names the entity ("joint 'pivot'")
/// and the argument at fault as the case format names it ("a/body", "node_set"; empty for the
/// entity as a whole), but no file or JSON path:  "joint 'pivot', a/body: unknown body 'crnk'".
/// The JSON loader maps the argument to the JSON path of the entry it reads.
class ModelError : public Error {
 public:
  ModelError(std::string entity, std::string field, std::string message)
      : Error(format(entity, field, message)),
        entity_(std::move(entity)),
        field_(std::move(field)),
        message_(std::move(message)) {}

  const std::string& entity() const { return entity_; }    ///< "joint 'pivot'", or empty
  const std::string& field() const { return field_; }      ///< "a/body", or empty
  const std::string& message() const { return message_; }  ///< what is wrong, without the names

 private:
  static std::string format(const std::string& entity, const std::string& field,
                            const std::string& message) {
    std::string out = entity;
    if (!field.empty()) out += (out.empty() ? "" : ", ") + field;
    return out.empty() ? message : out + ": " + message;
  }
  std::string entity_, field_, message_;
};

/// An output that could not be written although its folder was checked before the run (a full
/// disk, a quota, an I/O error): exit code 1, the run flagged partial. The message names the file
/// and the system's reason ("No space left on device").
class OutputError : public std::runtime_error {
 public:
  explicit OutputError(const std::string& message) : std::runtime_error(message) {}
};

/// A numerical failure (Newton divergence, singular matrix, NaN): exit code 1.
class NumericalFailure : public std::runtime_error {
 public:
  explicit NumericalFailure(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace lsmbs
