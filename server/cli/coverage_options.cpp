#include "server/cli/coverage_options.hpp"

#include <fstream>

#include "server/http/http_types.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/zones_json.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "core/common/strings.hpp"
#include "core/coverage/coverage_params.hpp"
#include "core/planning/rover_limits.hpp"

namespace rover::cli {

// "x,y,deg;x,y,deg" -> rover starts (local frame, heading converted to radians).
std::vector<RoverStart> readStartOption(const ArgParser& args) {
  std::vector<RoverStart> out;
  if (!args.has("start")) return out;
  std::stringstream all(args.str("start", ""));
  for (std::string one; std::getline(all, one, ';');) {
    std::vector<double> v;
    std::stringstream ss(one);
    for (std::string item; std::getline(ss, item, ',');) {
      char* end = nullptr;
      double d = std::strtod(item.c_str(), &end);
      if (item.empty() || *end != '\0' || !std::isfinite(d))
        throw UsageError("invalid value for --start: '" + one + "' is not X,Y,DEG");
      v.push_back(d);
    }
    if (v.size() != 3) throw UsageError("invalid value for --start: '" + one + "' is not X,Y,DEG");
    out.push_back({{v[0], v[1]}, v[2] * std::numbers::pi / 180.0});
  }
  if (out.empty() || out.size() > static_cast<std::size_t>(planning::kMaxRovers))
    throw UsageError("invalid value for --start: 1 to " + std::to_string(planning::kMaxRovers) + " rovers");
  return out;
}

std::string optionForParam(const std::string& key) {
  if (key == "sense_radius") return "sense";
  std::string o = key;
  std::replace(o.begin(), o.end(), '_', '-');
  return o;
}

void throwAsUsage(const Error& e) {
  if (e.field().empty()) throw UsageError(e.what());
  std::string msg = e.what();
  const std::string prefix = e.field() + ": ";
  if (msg.rfind(prefix, 0) == 0) msg = msg.substr(prefix.size());
  throw UsageError("invalid value for --" + optionForParam(e.field()) + ": " + msg);
}

void addWorldOptions(ArgParser& a) {
  a.option("rows", "N", "60", "Grid rows.");
  a.option("cols", "N", "60", "Grid columns.");
  a.option("cell", "M", "1.0", "Cell size in metres.");
  a.option("obstacles", "F", "0.05", "Fraction of cells that are obstacles, placed at random.");
  a.option("seed", "S", "1", "Seed for the obstacles and the rovers' random starts.");
  a.option("rovers", "N", "1", "Number of rovers (random distinct starts and headings).");
  a.flag("no-sealed",
         "Forbid free regions sealed off by obstacles (paper 002's single-rover "
         "study); by default they may occur and are reported as unreachable.");
}

coverage::WorldParams readWorldOptions(const ArgParser& a) {
  coverage::WorldParams w;
  w.rows = static_cast<int>(a.integer("rows", w.rows, 2, 4096));
  w.cols = static_cast<int>(a.integer("cols", w.cols, 2, 4096));
  w.cellSize = a.real("cell", w.cellSize, 1e-3, 1e4);
  w.obstacleFraction = a.real("obstacles", w.obstacleFraction, 0.0, 0.9);
  w.seed = static_cast<std::uint64_t>(a.integer("seed", 1, 0, INT64_MAX));
  w.allowSealed = !a.isSet("no-sealed");
  return w;
}

void addCoverageParamOptions(ArgParser& a) {
  addParamOptions(a, coverage::coverageParamTable().infos());
}

void addParamOptions(ArgParser& a, const std::vector<ParamInfo>& infos,
                     const std::vector<std::string>& skip) {
  for (const ParamInfo& info : infos) {
    if (std::find(skip.begin(), skip.end(), info.key) != skip.end()) continue;
    std::string help = info.doc;
    if (!info.unit.empty()) help += " [" + info.unit + "]";
    const std::string name = optionForParam(info.key);
    switch (info.type) {
      case ParamType::Bool:
        // A pair, because a planner may turn a flag on by default for some problems (coverage's
        // frontier mode on a DEM): --NAME sets it, --no-NAME clears it.
        a.flag(name, help);
        a.flag("no-" + name, "Turn --" + name + " off.");
        break;
      case ParamType::Choice: {
        a.option(name, join(info.choices, "|"), paramToString(info.defaultValue), help);
        break;
      }
      case ParamType::RealList:
        a.option(name, "V,V,...", "", help);
        break;
      default:
        a.option(name, info.type == ParamType::Int ? "N" : "X", paramToString(info.defaultValue),
                 help);
    }
  }
}

ParamSet readParamOptions(const ArgParser& a, const std::vector<ParamInfo>& infos,
                          const std::vector<std::string>& skip) {
  ParamSet set;
  for (const ParamInfo& info : infos) {
    const std::string name = optionForParam(info.key);
    if (std::find(skip.begin(), skip.end(), info.key) != skip.end()) continue;
    if (info.type == ParamType::Bool && a.has("no-" + name)) {
      if (a.has(name)) throw UsageError("--" + name + " and --no-" + name + " contradict each other");
      set[info.key] = false;
      continue;
    }
    if (!a.has(name)) continue;
    switch (info.type) {
      case ParamType::Bool:
        set[info.key] = true;
        break;
      case ParamType::Int:
        set[info.key] = static_cast<std::int64_t>(a.integer(name, 0, INT64_MIN, INT64_MAX));
        break;
      case ParamType::Real:
        set[info.key] = a.real(name, 0, -1e300, 1e300);
        break;
      case ParamType::Choice:
        set[info.key] = a.str(name, "");
        break;
      case ParamType::RealList:
        set[info.key] = a.realList(name);
        break;
    }
  }
  return set;
}

ParamSet readCoverageParamOptions(const ArgParser& a) {
  ParamSet set = readParamOptions(a, coverage::coverageParamTable().infos());
  // Paper 000 eq. 3 has α + β = 1: giving one implies the other.
  // Only a weight that is itself in range implies the other, so a bad one is reported by name.
  auto implies = [&](const char* given, const char* other) {
    if (!set.count(given) || set.count(other)) return;
    double v = std::get<double>(set[given]);
    if (v >= 0.0 && v <= 1.0) set[other] = 1.0 - v;
  };
  implies("beta", "alpha");
  implies("alpha", "beta");
  if (set.count("cost_table") && !set.count("pattern")) set["pattern"] = std::string("custom");
  return set;
}

}  // namespace rover::cli

namespace rover::cli {

void addKeepOutOption(ArgParser& args) {
  args.option("keep-out", "FILE", "",
              "Keep-out zones: a GeoJSON FeatureCollection of Polygons in the local frame (metres "
              "from the lower-left corner); every planner keeps out of them.");
}

KeepOut readKeepOutOption(const ArgParser& args, const GridGeometry& map) {
  if (!args.has("keep-out")) return {};
  const std::string path = args.str("keep-out", "");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError("invalid value for --keep-out: " + path + ": cannot read");
  std::string text(json::kMaxZonesFileBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  try {
    const nlohmann::json body = json::parseJsonLimited(text, {json::kMaxZonesFileBytes, 64});
    if (body.contains("crs"))
      throw UsageError("invalid value for --keep-out: " + path +
                       ": the file names a CRS; give the zones in the local frame (or import it "
                       "into a map with PUT /api/maps/{id}/zones?crs=map)");
    return json::zonesFromJson(body, "zones", &map);
  } catch (const http::ApiError& e) {
    throw UsageError("invalid value for --keep-out: " + path + ": " + e.what());
  }
}

}  // namespace rover::cli
