#pragma once
// What `roverplan study summary` and `roverplan sweep` print and write: the per-configuration table
// (mean, std, p5, p50, p95 per metric) and summary.json / summary.csv.
#include <filesystem>
#include <iosfwd>

#include <nlohmann/json.hpp>

#include "server/studies/study_db.hpp"

namespace rover::cli {

void printSummaryTable(std::ostream& out, const studies::StudySummary& s);
// summary.json (toJson(s) merged with `extra`) and summary.csv in `dir`; throws UsageError when
// the directory cannot be written.
void writeSummaryFiles(const std::filesystem::path& dir, const studies::StudySummary& s, const nlohmann::json& extra);

}  // namespace rover::cli
