#include "lsmbs/io/initial_state_file.hpp"

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "lsmbs/core/file_check.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/core/text.hpp"

namespace lsmbs {

namespace fs = std::filesystem;

namespace {

constexpr const char* kFormat = "lsmbs final state";

// The velocities of unknowns [first, end) are given: held by the projection, and a conflict with
// the joints is reported at `path` (the key `label` stands for it in Case::paths).
void hold(ModelStart& st, std::map<std::string, std::string>& paths, const std::string& label,
          const std::string& path, int first, int end) {
  if (st.held_velocities.size() < static_cast<size_t>(end))
    st.held_velocities.resize(static_cast<size_t>(end), 0);
  for (int i = first; i < end; ++i) st.held_velocities[static_cast<size_t>(i)] = 1;
  paths[label] = path;
  st.given_velocities.push_back({label, "", first, end});
}

std::string read_text(const std::string& path, const JsonReader& at, const std::string& key) {
  if (const auto why = unreadable_file_reason(path); !why.empty()) at.fail(key, path + ": " + why);
  std::ifstream f(path, std::ios::binary);
  if (!f) at.fail(key, path + ": cannot open the file");
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// "from": the earlier run's state, body by body (every body of this case must be in it, with the
// same kind and node count)
std::string from_run(const JsonReader& r, const Model& m, const std::string& file, ModelStart& st) {
  const std::string text = read_text(file, r, "from");
  nlohmann::json j;
  try {
    j = parse_json_document(text, file);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(file, "", std::string("invalid JSON: ") + e.what());
  }
  const JsonReader doc(j, file);
  if (!doc.is_object() || !j.contains("format") || j["format"] != kFormat)
    doc.fail("expected a final_state.json written by lsmbs simulate (\"format\": \"" +
             std::string(kFormat) + "\")");
  if (doc.string("status") != "complete")
    doc.fail("status", "the run that wrote this state did not complete (status '" +
                           doc.string("status") +
                           "'): its last state is not one it reached; start from a complete run");
  if (doc.integer("version", 0) != 1)
    doc.fail("version", "expected 1 (the final_state.json format this lsmbs writes)");
  doc.number("t");  // a number (the time the state was reached; the run starts at its own t = 0)
  std::map<std::string, JsonReader> bodies;
  for (const auto& b : doc.items("bodies", true))
    if (!bodies.emplace(b.string("name"), b).second)
      b.fail("name", "body '" + b.string("name") + "' is listed twice");
  auto vec_of = [&](const JsonReader& b, const std::string& key, size_t n) {
    const nlohmann::json& a = b.child(key).raw();
    if (!a.is_array() || a.size() != n)
      b.fail(key, "expected an array of " + std::to_string(n) + " numbers");
    std::vector<double> v;
    for (size_t k = 0; k < n; ++k) {
      if (!a[k].is_number()) b.fail(key, "expected numbers");
      v.push_back(a[k].get<double>());
      if (!std::isfinite(v.back())) b.fail(key, "expected finite numbers");
    }
    return v;
  };
  const std::string path = r.path() + "/from";
  auto find = [&](const std::string& name, const char* kind) -> const JsonReader& {
    const auto it = bodies.find(name);
    if (it == bodies.end())
      r.fail("from", file + " holds no body '" + name + "' (" + kind +
                         " in this case): start from a run of the same model");
    if (it->second.string("type") != kind)
      r.fail("from", file + ": body '" + name + "' is " + it->second.string("type") +
                         " there and " + kind + " in this case");
    return it->second;
  };
  for (const auto& rb : m.rigid_bodies()) {
    const JsonReader& b = find(rb.name, "rigid");
    const auto q = vec_of(b, "q", 3), v = vec_of(b, "v", 3);
    for (int k = 0; k < 3; ++k) {
      st.placed.q[rb.dof0 + k] = q[static_cast<size_t>(k)];
      st.placed.v[rb.dof0 + k] = v[static_cast<size_t>(k)];
    }
    bodies.erase(rb.name);
  }
  for (const auto& fb : m.flexible_bodies()) {
    const JsonReader& b = find(fb->name, "flexible");
    const int n = fb->mesh.num_nodes();
    if (b.integer("nodes", 0) != n)
      r.fail("from", file + ": body '" + fb->name + "' has " +
                         std::to_string(b.integer("nodes", 0)) + " nodes there and " +
                         std::to_string(n) + " in this case (the same mesh is needed)");
    const auto q = vec_of(b, "q", 2 * static_cast<size_t>(n)),
               v = vec_of(b, "v", 2 * static_cast<size_t>(n));
    for (int k = 0; k < 2 * n; ++k) {
      st.placed.q[fb->dof0 + k] = q[static_cast<size_t>(k)];
      st.placed.v[fb->dof0 + k] = v[static_cast<size_t>(k)];
    }
    bodies.erase(fb->name);
  }
  if (!bodies.empty())
    r.fail("from", file + " holds body '" + bodies.begin()->first +
                       "', which this case does not have: start from a run of the same model");
  return doc.one_of("source", {"simulate", "static"});
}

// "nodes": [{"body", "file"}]: per node of the body's mesh, in order, ux, uy (from the placed
// position) and vx, vy; a header line names the columns (an optional first column "node" is
// checked against the row).
void nodal(const JsonReader& e, const Model& m, const std::string& file, ModelStart& st,
           std::map<std::string, std::string>& paths, const std::string& path) {
  const std::string name = e.string("body");
  const FlexibleBody* fb = m.find_flexible(name);
  if (!fb) {
    for (const auto& rb : m.rigid_bodies())
      if (rb.name == name)
        e.fail("body", "body '" + name +
                           "' is rigid: nodal states are for flexible bodies (a rigid body's "
                           "state comes from \"from\", or its own position and velocity)");
    e.fail("body", "unknown flexible body '" + name + "'");
  }
  const std::string text = read_text(file, e, "file");
  std::istringstream in(text);
  std::string line;
  int lineno = 0, row = 0;
  bool header = false, with_node = false;
  const int n = fb->mesh.num_nodes();
  auto fail = [&](const std::string& what) {
    throw Error(file, "line " + std::to_string(lineno), what);
  };
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> f;
    std::string cell;
    std::istringstream ls(line);
    while (std::getline(ls, cell, ',')) {
      const auto a = cell.find_first_not_of(" \t"), b = cell.find_last_not_of(" \t");
      f.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
    }
    if (!line.empty() && line.back() == ',') f.push_back("");
    if (!header) {
      const std::vector<std::string> plain = {"ux", "uy", "vx", "vy"},
                                     numbered = {"node", "ux", "uy", "vx", "vy"};
      if (f != plain && f != numbered)
        fail("expected the header 'ux,uy,vx,vy' or 'node,ux,uy,vx,vy', got " + shown(line));
      header = true;
      with_node = f.size() == 5;
      continue;
    }
    const size_t cols = with_node ? 5 : 4;
    if (f.size() != cols)
      fail("expected " + std::to_string(cols) + " comma-separated fields, got " +
           std::to_string(f.size()) + ": " + shown(line));
    if (row >= n) fail("more rows than the " + std::to_string(n) + " nodes of body '" + name + "'");
    if (with_node) {
      const auto k = parse_integer(f[0]);
      if (!k || *k != row)
        fail("expected node " + std::to_string(row) + " (rows in node order, from 0), got " +
             shown(f[0]));
    }
    double x[4];
    for (int c = 0; c < 4; ++c) {
      const auto v = parse_finite_double(f[static_cast<size_t>(c) + (with_node ? 1 : 0)]);
      if (!v)
        fail("expected a finite number for " + std::string(c < 2 ? "u" : "v") +
             (c % 2 ? "y" : "x") + ", got " +
             shown(f[static_cast<size_t>(c) + (with_node ? 1 : 0)]));
      x[c] = *v;
    }
    const int d = fb->node_dof(row);
    st.placed.q[d] += x[0];
    st.placed.q[d + 1] += x[1];
    st.placed.v[d] = x[2];
    st.placed.v[d + 1] = x[3];
    ++row;
  }
  if (!header) throw Error(file, "", "expected the header 'ux,uy,vx,vy' and a row per node");
  if (row != n)
    throw Error(file, "",
                "holds " + std::to_string(row) + " rows, body '" + name + "' has " +
                    std::to_string(n) + " nodes (a row per node, in node order)");
  hold(st, paths, "initial_state:nodes:" + name, path, fb->dof0, fb->dof0 + 2 * n);
}

}  // namespace

nlohmann::json final_state_json(const Model& m, const State& s, const std::string& case_name,
                                const std::string& status, const std::string& source) {
  nlohmann::json bodies = nlohmann::json::array();
  for (const auto& rb : m.rigid_bodies())
    bodies.push_back({{"name", rb.name},
                      {"type", "rigid"},
                      {"q", {s.q[rb.dof0], s.q[rb.dof0 + 1], s.q[rb.dof0 + 2]}},
                      {"v", {s.v[rb.dof0], s.v[rb.dof0 + 1], s.v[rb.dof0 + 2]}}});
  for (const auto& fb : m.flexible_bodies()) {
    const int n = fb->mesh.num_nodes();
    std::vector<double> q(s.q.data() + fb->dof0, s.q.data() + fb->dof0 + 2 * n),
        v(s.v.data() + fb->dof0, s.v.data() + fb->dof0 + 2 * n);
    bodies.push_back({{"name", fb->name}, {"type", "flexible"}, {"nodes", n}, {"q", q}, {"v", v}});
  }
  return {{"format", kFormat},
          {"version", 1},
          {"case_name", case_name},
          {"status", status},
          {"source", source},
          {"t", s.t},
          {"description",
           "every body's unknowns q and rates v at time t (rigid: x, y, theta; flexible: x, y of "
           "each node in mesh order); a case starts from it with \"initial_state\": {\"from\": "
           "\"<this file>\"}"},
          {"bodies", bodies}};
}

void read_initial_state(const JsonReader& r, const Model& m, const std::string& base_dir,
                        ModelStart& st, std::map<std::string, std::string>& paths,
                        std::string& note, std::set<std::string>& files) {
  auto resolve = [&](const std::string& f) {
    const std::string path = fs::path(f).is_absolute() ? f : (fs::path(base_dir) / f).string();
    files.insert(path);
    return path;
  };
  st.placed.v.conservativeResize(m.nq());
  if (r.has("from")) {
    const std::string file = resolve(r.string("from"));
    if (from_run(r, m, file, st) == "static")
      note = "the initial state is the static equilibrium in " + file +
             ", computed at one design: the gradients treat it as fixed data (its design "
             "derivative is not included)";
  }
  size_t k = 0;
  std::set<std::string> seen;
  for (const auto& e : r.items("nodes")) {
    if (!seen.insert(e.string("body")).second)
      e.fail("body", "body '" + e.string("body") + "' has two entries");
    nodal(e, m, resolve(e.string("file")), st, paths, r.path() + "/nodes/" + std::to_string(k++));
    e.finish();
  }
  // an element folded or inverted at the start is an input error, not a failure of step 1
  const auto inv = m.most_compressed_element(st.placed.q, m.params());
  if (inv.folded())
    r.fail("the initial state folds or inverts an element: " + inv.describe_fold() +
           " (det F <= 0 at t = 0): check the displacements against the mesh");
  if (!r.has("from") && k == 0)
    r.fail("expected \"from\" (an earlier run's final_state.json) or \"nodes\"");
  r.finish();
}

}  // namespace lsmbs
