#pragma once
// Initial states from data: the final state of an earlier run (final_state.json, written by
// simulate) and nodal displacements and velocities of a flexible body (a CSV file). Both are data
// of the case, not of the design: they do not depend on p, so every sensitivity method stays exact
// (q0 and q̇0 carry no design derivative, as for a placed start). Both go through the same
// consistency projection and start checks as a placed start (prepare_case). Nodal velocities are
// held as given (a contradiction with the joints is refused, naming /initial_state/nodes/<i>);
// an earlier run's velocities are projected like its positions (smallest change), since
// generalized-α meets the velocity constraints only to its discretization error. Positions that
// contradict the joints and drivers at t = 0 are refused naming the body.
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "lsmbs/io/case.hpp"
#include "lsmbs/io/json_reader.hpp"

namespace lsmbs {

/// final_state.json of a run: every body's unknowns and their rates at the state reached, by body
/// name (rigid: x, y, θ; flexible: each node's position), exact doubles.
/// `source`: "simulate" or "static" (a static equilibrium, which depends on the design).
nlohmann::json final_state_json(const Model& model, const State& s, const std::string& case_name,
                                const std::string& status, const std::string& source);

/// Reads the case's "initial_state" section (`r`) into `start` (an entry that gives velocities is
/// added to `paths` under its label, for the start checks' messages): "from" (an earlier run's
/// final_state.json) and "nodes" (per flexible body, a CSV of ux, uy, vx, vy per node). File names
/// are relative to `base_dir`. Throws Error naming the file (and line) or the JSON path.
/// A state that a static analysis computed sets `note` (Study::initial_state_note).
/// Every file it reads is added to `files`.
void read_initial_state(const JsonReader& r, const Model& model, const std::string& base_dir,
                        ModelStart& start, std::map<std::string, std::string>& paths,
                        std::string& note, std::set<std::string>& files);

}  // namespace lsmbs
