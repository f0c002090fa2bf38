#pragma once
// Output writers. Every file is written atomically (core/json_file.hpp: write_file_atomic,
// write_json_atomic), so an interrupted run never leaves a half-written file that looks complete.
//  * write_csv: a header and rows (names quoted where RFC 4180 needs it, so that any CSV reader,
//    pandas.read_csv without options included, reads the columns back; numbers that read back as
//    the same doubles);
//  * write_vtu: one flexible body at one instant (ParaView), with displacement, μ_e and the
//    von Mises stress of the Cauchy stress at the element centre;
//  * write_pvd: the time series of VTU files.
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "lsmbs/core/csv.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/mbs/model.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

void write_csv(const std::string& path, const std::vector<std::string>& header,
               const std::vector<std::vector<double>>& rows);
void write_vtu(const std::string& path, const FlexibleBody& body, const Vec& q,
               const ModelParams& p);
/// A design on its mesh (body frame, undeformed): the level set φ at the nodes (material where
/// φ > 0; a contour at 0 is the features' boundary) and μ_e per element.
void write_design_vtu(const std::string& path, const Mesh2D& mesh, const Vec& mu, const Vec& phi);
void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& entries);

/// summary.json["units"]: the SI unit of the time column ("t": "s"), of every measure column
/// ("measures", as in history.csv) and of every response ("responses"); docs/case-format.md.
nlohmann::json units_json(const Study& s);

/// summary.json["files"]: the files a command wrote, relative to its output folder, sorted and
/// without duplicates (summary.json itself included by the caller).
nlohmann::json file_list(std::vector<std::string> files);

/// Provenance block of every summary.json: version, git commit, case file and hash.
nlohmann::json provenance(const std::string& command, const std::string& case_file,
                          const std::string& case_sha256);

}  // namespace lsmbs
