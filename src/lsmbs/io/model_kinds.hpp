#pragma once
// The table of model kinds: every joint, force, measure and level-set feature a case can name,
// with its keys (type, required or not, how Python passes it, what it means) and the function that
// reads an entry of that kind into the model. The JSON loader reads joints, forces and measures
// through it (io/case_loader.cpp) and takes the feature parameters from it; the Python builder
// (python/lsmbs/builder.py) makes its methods from it (lsmbs._lsmbs.model_kinds()); a test checks
// that docs/case-format.md names every kind and key. A new joint, force or measure is one entry
// here, plus its element or measure class and its tests (docs/extending.md).
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lsmbs/io/json_reader.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/mbs/table.hpp"
#include "lsmbs/mbs/time_law.hpp"
#include "lsmbs/responses/measure.hpp"

namespace lsmbs {

/// The value a key takes.
enum class KeyType {
  kNumber,       ///< any finite number
  kNonNegative,  ///< a number >= 0
  kPositive,     ///< a number > 0
  kInteger,      ///< an integer
  kBoolean,
  kName,           ///< the name of a body, joint, driver or node set
  kVec2,           ///< [x, y]
  kVec3,           ///< [x, y, z] (spatial cases)
  kPoint,          ///< a material point ({"ground": [x, y]}, {"body": …, "at": …}, …)
  kPointOrGround,  ///< a point, or "ground" (the ground point at the other end's start)
  kLaw,            ///< a time law ({"type": "trapezoid" | "ramp" | "table" | "constant", …})
  kTable,          ///< a table ({"points": [[x, y], …]} or {"file": …}, interpolation, …)
  kParameter,      ///< a feature parameter: a number, a design variable's name, or {variable, …}
  kJson            ///< an object or list the kind reads itself (documented with the kind)
};
const char* key_type_name(KeyType t);

struct KindKey {
  std::string name;
  KeyType type = KeyType::kNumber;
  bool required = false;
  /// Python passes it by position, in the table's order (the others by keyword only).
  bool positional = false;
  /// The value Python's builder writes when the argument is not given (JSON text; empty: none,
  /// the key is left out and the case format's default applies).
  std::string python_default;
  std::string doc;
};

class KindReader;

struct ModelKind {
  std::string section;        ///< "joints", "forces", "measures" or "features"
  std::string type;           ///< the entry's "type"
  std::string doc;            ///< one sentence: what it is
  std::vector<KindKey> keys;  ///< besides "name" and "type"
  /// Reads one entry of this kind (its name already read and checked) into the model; the
  /// features' entries are read by the design section of the loader.
  std::function<void(KindReader&, const JsonReader&, const std::string& name)> read;
};

/// What reading an entry needs from the loader that holds the model under construction.
class KindReader {
 public:
  virtual ~KindReader() = default;
  virtual ModelBuilder& builder() = 0;
  virtual Point point(const JsonReader& r) = 0;
  virtual std::shared_ptr<const TimeLaw> law(const JsonReader& r) = 0;
  virtual Table1D table(const JsonReader& r) = 0;
  /// A measure of the case (its name checked to be new).
  virtual void add_measure(std::unique_ptr<Measure> m) = 0;
  /// A constraint-force measure, made once the model is built (the joint's rows are known then).
  virtual void add_constraint_force(const std::string& name, const std::string& joint) = 0;
  /// The weighted sum of earlier measures' columns (the "combination" measure).
  virtual std::unique_ptr<Measure> combination(const JsonReader& r, const std::string& name) = 0;
  /// Runs a builder call for the entry `r`: its ModelError is reported at the JSON path of the
  /// argument it names (below r), or at r.
  void at_entry(const JsonReader& r, const std::function<void()>& call);
  /// Runs a query by name given under key `key` of r: its error is reported at that key.
  template <class F>
  decltype(auto) at_key(const JsonReader& r, const std::string& key, F&& call) {
    try {
      return call();
    } catch (const ModelError& e) {
      r.fail(key, e.message());
    }
  }
};

/// Every kind, by section, in the order of the case format's documentation.
const std::vector<ModelKind>& model_kinds();
/// The kind of `type` in `section`, or null.
const ModelKind* find_kind(const std::string& section, const std::string& type);
/// The types of a section, in the table's order.
std::vector<std::string> kind_types(const std::string& section);
/// The same lookups in a given table (the planar one or the spatial one).
const ModelKind* find_kind_in(const std::vector<ModelKind>& kinds, const std::string& section,
                              const std::string& type);
std::vector<std::string> kind_types_in(const std::vector<ModelKind>& kinds,
                                       const std::string& section);

/// The kinds of spatial cases ("dimension": 3; io/spatial_kinds.cpp): joints, drivers, forces and
/// measures of spatial rigid bodies, named like their planar counterparts where they have one.
const std::vector<ModelKind>& spatial_model_kinds();
/// A stress measure's aggregation options ("aggregate", "reference", "parameter", "relaxation").
StressMeasure::Options stress_options(const JsonReader& r);
/// Its kind's keys: `body` (documented as `body_doc`; Python passes it by position where
/// `body_positional`) and the options stress_options reads.
std::vector<KindKey> stress_keys(const std::string& body_doc, bool body_positional);
const ModelKind* find_spatial_kind(const std::string& section, const std::string& type);
std::vector<std::string> spatial_kind_types(const std::string& section);

}  // namespace lsmbs
