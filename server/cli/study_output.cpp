#include "server/cli/study_output.hpp"

#include <fstream>
#include <iomanip>
#include <ostream>

#include "server/cli/arg_parser.hpp"

namespace rover::cli {

void printSummaryTable(std::ostream& out, const studies::StudySummary& s) {
  out << std::left << std::setw(24) << "config" << std::setw(26) << "metric" << std::right << std::setw(6) << "n"
      << std::setw(12) << "mean" << std::setw(12) << "std" << std::setw(12) << "p5" << std::setw(12) << "p50"
      << std::setw(12) << "p95" << "\n";
  const auto flags = out.flags();
  const auto precision = out.precision();
  out << std::fixed << std::setprecision(4);
  std::string last;
  for (const auto& r : s.rows) {
    if (!last.empty() && r.config != last) out << "\n";
    last = r.config;
    out << std::left << std::setw(24) << r.config << std::setw(26) << r.metric << std::right << std::setw(6)
        << r.summary.count << std::setw(12) << r.summary.mean << std::setw(12) << r.summary.stddev << std::setw(12)
        << r.summary.p5 << std::setw(12) << r.summary.p50 << std::setw(12) << r.summary.p95 << "\n";
  }
  out.flags(flags);
  out.precision(precision);
}

void writeSummaryFiles(const std::filesystem::path& dir, const studies::StudySummary& s, const nlohmann::json& extra) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  nlohmann::json j = studies::toJson(s);
  for (const auto& [k, v] : extra.items()) j[k] = v;
  std::ofstream csv(dir / "summary.csv");
  csv << "config,metric,runs,n,mean,std,p5,p50,p95,min,max\n";
  for (const auto& r : s.rows) {
    const Summary& m = r.summary;
    csv << r.config << "," << r.metric << "," << r.runs << "," << m.count << "," << m.mean << "," << m.stddev << ","
        << m.p5 << "," << m.p50 << "," << m.p95 << "," << m.min << "," << m.max << "\n";
  }
  std::ofstream json(dir / "summary.json");
  json << j.dump(2) << "\n";
  if (!csv || !json) throw UsageError("cannot write to --out " + dir.string());
}

}  // namespace rover::cli
