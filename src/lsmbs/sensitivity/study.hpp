#pragma once
// Study — what a simulation, a sensitivity analysis or an optimization needs, whatever built it
// (a case file, or code): the model, its initial state, the generalized-α options, the measures
// recorded at every step, the responses aggregated from them and, optionally, the design
// variables. Responses name their measure column; the library reports errors by these names.
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "lsmbs/design/design.hpp"
#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/mbs/model.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/responses/measure.hpp"

namespace lsmbs {

struct Study {
  std::unique_ptr<Model> model;
  State initial;
  /// Non-empty when the initial state is data that was itself computed at one design (a static
  /// equilibrium read from a file): gradients treat it as fixed, and the runs say so.
  std::string initial_state_note;
  GeneralizedAlphaOptions simulation;
  std::vector<std::unique_ptr<Measure>> measures;
  std::vector<ResponseSpec> responses;
  /// Null without design variables; when present, the model parameters hold a design of it.
  std::unique_ptr<Design> design;
  /// What the building of the model knew, for the start checks (ModelBuilder::start); empty for
  /// a study made from a model and a state alone.
  ModelStart start;
  /// Refuse redundant or conflicting constraints in prepare() (false only for models that are
  /// evaluated, never integrated, e.g. derivative tests).
  bool check_constraints = true;

  // ---------------------------------------------------------- building a study in code
  /// Takes the model and its initial state (e.g. ModelBuilder::build() and initial_state()).
  Study(std::unique_ptr<Model> m, State s0, GeneralizedAlphaOptions o)
      : model(std::move(m)), initial(std::move(s0)), simulation(std::move(o)) {}
  /// Takes the model of a builder and what the start checks need of it (ModelBuilder::build(),
  /// initial_state() and start()).
  Study(ModelBuilder& builder, GeneralizedAlphaOptions o);
  Study() = default;
  /// Adds a measure; its names must be new (SetupError "measures" otherwise).
  Measure& add_measure(std::unique_ptr<Measure> m);
  /// Adds a response of the measure column `measure` (a measure's name, or "name.x" / "name.y"
  /// for a point's components), aggregated over [t0, t1]; SetupError "responses" for an unknown
  /// column or a name in use.
  ResponseSpec& add_response(const std::string& name, const std::string& measure,
                             ResponseSpec::Kind kind, double t0 = -1e300, double t1 = 1e300);
  /// Sets the design variables and writes their initial values into the model's parameters.
  void set_design(std::unique_ptr<Design> d);

  /// The start checks, the same for a study built in code, by the Python builder or from a case
  /// file: valid simulation options, independent constraints at t = 0, a time step in every
  /// response window, finite forces and iteration matrix at the start with `design` (or the
  /// initial design) written into the model's parameters, given velocities the joints allow (they
  /// are kept, the others projected: `initial` is set), bodies placed where the joints and drivers
  /// put them at t = 0, finite measures. Throws SetupError naming the subject or the entity (a
  /// body, joint or force by name). Call it after the last change of the study and before a run.
  void prepare(const Vec* design = nullptr);

  /// Column names of the measure history (in the order measures are evaluated).
  std::vector<std::string> measure_columns() const;
  /// SI unit of each measure column (Measure::units), in the order of measure_columns().
  std::vector<std::string> measure_units() const;
  /// SI unit of response r (ResponseSpec::unit of its measure column's unit).
  std::string response_unit(size_t r) const;
  /// Index of the measure column `name`, −1 if there is none.
  int measure_column(const std::string& name) const;
  /// Index of the response `name`, −1 if there is none.
  int response_index(const std::string& name) const;

  /// For callers that change the study while others run from it: the Python module holds it from
  /// writing a run's design into the model's parameters (the start checks) to the end of the run,
  /// so that two threads sharing one case take turns. Evaluations of sensitivities do not need
  /// it: they run with their own copy of the parameters (parameters_at, sensitivity.hpp) and may
  /// run at once. Recursive: a run may start runs of its own.
  std::recursive_mutex& evaluation_mutex() const { return evaluation_.mutex; }

 private:
  struct EvaluationMutex {  // a moved study gets a mutex of its own (a mutex cannot move)
    mutable std::recursive_mutex mutex;
    EvaluationMutex() = default;
    EvaluationMutex(EvaluationMutex&&) noexcept {}
    EvaluationMutex& operator=(EvaluationMutex&&) noexcept { return *this; }
  } evaluation_;
};

}  // namespace lsmbs
