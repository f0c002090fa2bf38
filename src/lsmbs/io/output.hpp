#pragma once
// Output writers. Every file is written atomically (core/json_file.hpp: write_file_atomic,
// write_json_atomic), so an interrupted run never leaves a half-written file that looks complete.
//  * write_csv: a header and rows (names quoted where RFC 4180 needs it, so that any CSV reader,
//    pandas.read_csv without options included, reads the columns back; numbers that read back as
//    the same doubles);
//  * write_vtu / write_rigid_vtu / write_model_vtk: the bodies at one instant (ParaView; the
//    conventions are in docs/case-format.md, "VTK files"): a flexible body's quads at the deformed
//    points with total_displacement, elastic_displacement, μ_e and the von Mises stress of the
//    Cauchy stress at the element centre; a rigid body's outline (rigid_outline) with the same two
//    displacement arrays; one multiblock .vtm per instant that lists every body;
//  * write_design_vtu: a design on its mesh (level set φ and μ_e);
//  * write_pvd: a time series of VTU or VTM files.
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "lsmbs/core/csv.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/mbs/model.hpp"
#include "lsmbs/sensitivity/conditions.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

struct Case;

/// `poll`, when given, is called every few thousand rows (a long history: it may throw to stop).
void write_csv(const std::string& path, const std::vector<std::string>& header,
               const std::vector<std::vector<double>>& rows,
               const std::function<void()>& poll = {});
/// A flexible body at positions q: points x, the quads, point data total_displacement x − X (X:
/// the placed mesh at t = 0) and elastic_displacement (x minus the rigid motion that fits the nodes
/// best in least squares), cell data mu and von_mises.
/// `cells`: further per-element arrays (name, one value per element), e.g. a stress measure's
/// relaxed von Mises stresses.
using CellArrays = std::vector<std::pair<std::string, std::vector<double>>>;
void write_vtu(const std::string& path, const FlexibleBody& body, const Vec& q,
               const ModelParams& p, const CellArrays& cells = {});
/// The body-frame points a rigid body is drawn with: the convex hull (counter-clockwise, collinear
/// points dropped) of its attachments (RigidBody::attachments) and of its centre of mass when that
/// is off the reference point; the reference point alone when nothing attaches. One point, two
/// (a line between the extreme joint points) or a polygon.
std::vector<Vec2> rigid_outline(const RigidBody& body);
/// A rigid body at positions q: its outline placed at (x, y, θ) as one cell (vertex, line or
/// polygon), point data total_displacement (from the placement at t = 0) and elastic_displacement
/// (zero), so that filters over all bodies find the same arrays as on the flexible ones.
void write_rigid_vtu(const std::string& path, const RigidBody& body, const Vec& q);
/// A spatial rigid body at positions q: its centre of mass (a vertex), a line to each point where
/// something attaches, and its principal axes (lines), with the total and (zero) elastic
/// displacement and the cell field `part` (0 centre, 1 attachment, 2 axis).
void write_spatial_vtu(const std::string& path, const SpatialRigidBody& body, const Vec& q);
/// A 3D solid body at positions q: its hexahedra and tetrahedra at the deformed nodes, point
/// data total_displacement (x − X) and elastic_displacement (x less the rigid motion that fits
/// the nodes best, Kabsch), cell data mu and von_mises (the Cauchy stress at the element centre
/// from its own strain, solid material); with phi, also the level set φ at the nodes (point data
/// "phi": material where φ > 0; its zero contour is the designed boundary).
void write_solid_vtu(const std::string& path, const SolidBody& body, const Vec& q,
                     const ModelParams& p, const Vec* phi = nullptr);
/// A design on its mesh (body frame, undeformed): the level set φ at the nodes (material where
/// φ > 0; a contour at 0 is the features' boundary) and μ_e per element.
void write_design_vtu(const std::string& path, const Mesh2D& mesh, const Vec& mu, const Vec& phi);
/// A VTK multiblock file: one block per (name, file), files relative to the .vtm's folder.
void write_vtm(const std::string& path,
               const std::vector<std::pair<std::string, std::string>>& blocks);
void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& entries);

/// The multiblock name of a model's VTK output (kModelVtk.pvd, vtu/kModelVtk_<step>.vtm); the case
/// loader refuses a body of that name while VTK files are written.
inline constexpr const char* kModelVtk = "model";

/// What write_model_vtk wrote, as paths relative to its output folder.
struct ModelVtkFiles {
  std::vector<std::pair<std::string, std::string>> bodies;  ///< body name, its VTU
  std::string multiblock;                                   ///< the .vtm listing them
};
/// Every body of the model at positions q, with the parameters (μ_e) of the run:
/// OUT/<folder><body><suffix>.vtu (flexible bodies first, then rigid ones, then spatial ones, each
/// in model order) and OUT/<folder>model<suffix>.vtm listing them (folder:
/// "" or ending in '/'; it must exist).
/// `stress`: stress measures whose relaxed element stresses are written as the cell array
/// "<measure>_relaxed_von_mises" of their body.
ModelVtkFiles write_model_vtk(const std::string& out_dir, const std::string& folder,
                              const std::string& suffix, const Model& model,
                              const ModelParams& params, const Vec& q,
                              const std::vector<const StressMeasure*>& stress = {});

/// The file-name stem of each body's files (<stem>.pvd, vtu/<stem>_<step>.vtu, <stem>.png):
/// core/text.hpp's file_stem of its name, made unique over the model's bodies (flexible ones first,
/// in order, then rigid ones) and distinct from kModelVtk by a suffix _2, _3, … Names are data: a
/// body called "../x" or "a\nb" writes _.._x.pvd and a_b.pvd inside the output folder.
std::map<std::string, std::string> body_file_stems(const Model& model);

/// summary.json["design"]: {variable: value} at the design point p (empty: the case's initial
/// design); null when the study has no design variables.
nlohmann::json design_json(const Study& s, const Vec& p = {});

/// summary.json["units"]: the SI unit of the time column ("t": "s"), of every measure column
/// ("measures", as in history.csv) and of every response ("responses"); docs/case-format.md.
nlohmann::json units_json(const Study& s);
/// The same over service conditions: every gathered response's unit (sensitivity/conditions.hpp).
nlohmann::json units_json(const Conditions& c);
/// summary.json["conditions"]: each condition (its name, what it sets, t_end, h), the combinations
/// (with the KS error bound), the responses evaluated once and every response's name.
nlohmann::json conditions_json(const Case& cs, const Conditions& c);

/// summary.json["files"]: the files a command wrote, relative to its output folder, sorted and
/// without duplicates (summary.json itself included by the caller).
nlohmann::json file_list(std::vector<std::string> files);

/// Provenance block of every summary.json: version, git commit, case file and hash.
nlohmann::json provenance(const std::string& command, const std::string& case_file,
                          const std::string& case_sha256);

}  // namespace lsmbs
