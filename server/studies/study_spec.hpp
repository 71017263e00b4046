#pragma once
// A study (issue 12): a planner, a grid of its parameters, worlds, a PDM source, a rover starts
// rule, runs per configuration and a master seed, as one JSON document. Validated at the edge into
// StudySpec; every error is a rover::Error whose field() is the JSON path of the offending value
// ("worlds[1].grid.rows", "grid.pattern[2]", "configs[0].params.route").
//
// The JSON (every key but "worlds" optional; unknown keys refused):
//   {
//     "name": "laine-fig6",            // shown in summaries
//     "planner": "coverage",           // a registered planner: coverage | team-search | hybrid
//     "runs": 3000,                    // seeded runs per configuration
//     "master_seed": 1,
//     "worlds": [                      // one configuration axis; each item one of
//       {"name": "60x60", "grid": {"rows": 60, "cols": 60, "cell_size": 1,
//                                  "obstacle_fraction": 0.05, "allow_sealed": false}},
//       {"name": "mars600", "terrain": {"preset": "mars", "size": 600, "cell_size": 0.25, "seed": 1}},
//       {"name": "hirise150", "dem": "path/to/file.tif", "cell_size": 0.25, "crop_m": 150}
//     ],                               // grid: a new random obstacle grid per run (its seed);
//                                      // terrain/dem: one map for every run (crop_m: centre square)
//     "rovers": [1],                   // team sizes, a configuration axis (an integer = one size)
//     "starts": "random",              // random: distinct free cells (seed = the run's seed);
//                                      // formation: the team formation at the map's centre
//     "pdm": {"random_gaussians": 4},  // team planners: G random Gaussians, seed = the run's seed
//     "params": {"coverage": 1.0},     // the planner's parameters common to every configuration
//     "grid": {"pattern": ["spiral", "boustrophedon"]},     // cartesian product of values per key
//     "configs": [{"name": "spiral+circ", "planner": "coverage", "params": {...}}],  // named points
//     "levels": [0.9, 1.0],            // coverage: path_length_ratio read at these coverage levels
//     "distances": [100, 200],         // team: accumulated probability read at these distances, m
//     "curve_points": 32,              // samples kept of each run's curve
//     "mission_threads": 1             // threads each run plans on
//   }
// Configurations = worlds × rovers × (configs × grid points); a configuration's name joins its
// world's name (when there are several worlds), "<N>r" (several team sizes) and its point's name.
// Parameter keys and values are checked against the planner's own table (core/common/params.hpp).
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/common/params.hpp"
#include "core/coverage/world.hpp"
#include "maps/synthetic_terrain.hpp"

namespace rover::studies {

struct WorldSpec {
  enum class Kind { Grid, Terrain, Dem };
  std::string name;
  Kind kind = Kind::Grid;
  coverage::WorldParams grid;            // Grid: the seed is replaced by each run's seed
  maps::SyntheticTerrainParams terrain;  // Terrain
  std::string demPath;                   // Dem
  double cellSize = 0;                   // Dem: resampled to this cell, m (0 = the file's)
  double cropM = 0;                      // Dem: the centre square of this side, m (0 = all)
};

// One point of the parameter grid: a planner and its parameters (typed by its table).
struct ParamPoint {
  std::string name;
  std::string planner;
  ParamSet params;
};

// One configuration of the study: config_id is its index in configurations().
struct Configuration {
  int id = 0;
  std::string name;
  std::size_t world = 0;  // index into StudySpec::worlds
  int rovers = 1;
  ParamPoint point;
};

struct StudySpec {
  std::string name;
  std::string planner;
  int runs = 1;                    // per configuration
  std::uint64_t masterSeed = 1;
  std::vector<WorldSpec> worlds;
  std::vector<int> rovers{1};
  std::string starts = "random";   // random | formation
  int pdmComponents = 0;           // 0 = no PDM
  std::vector<double> levels;
  std::vector<double> distances;
  int curvePoints = 32;
  unsigned missionThreads = 1;
  std::vector<Configuration> configurations;
  nlohmann::json json;  // the document as given: stored in the database, compared on resume/merge

  std::size_t runCount() const { return configurations.size() * static_cast<std::size_t>(runs); }
  // run_index = config_id · runs + replicate.
  const Configuration& configOf(std::size_t runIndex) const { return configurations[runIndex / runs]; }
  std::uint64_t replicateOf(std::size_t runIndex) const { return runIndex % runs; }
};

// A run's seed, from the master seed and the run's replicate index (its index within the
// configuration), so every configuration sees the same worlds, starts and PDMs (a paired
// comparison) and no process-global RNG is involved: deriveSeed (core/common/random.hpp,
// SplitMix64) of (master, replicate), kept to 62 bits so it fits every seed parameter.
std::uint64_t runSeed(std::uint64_t masterSeed, std::uint64_t replicate);

// Limits that keep a spec's memory bounded.
constexpr int kMaxRuns = 10'000'000;
constexpr std::size_t kMaxConfigurations = 10'000;
constexpr std::size_t kMaxStudyRuns = 10'000'000;  // configurations × runs

// Validates `spec` (see above); throws rover::Error with the offending field's JSON path.
StudySpec parseStudySpec(const nlohmann::json& spec);

// Today's experiment presets as study documents: laine-fig6, laine-fig8, frontier (paper 002,
// synthetic grids) and swinton (paper 001 on the synthetic Mars map and the HiRISE Gale patch).
struct PresetOptions {
  int runs = 0;                    // 0 = the preset's default (3000; frontier 1000; swinton 20)
  std::uint64_t masterSeed = 1;
  // swinton only:
  std::string hirisePath = "../shared/dems/mars_gale_hirise_1m/missionDEM.tif";  // "" = synthetic only
  std::vector<std::string> configs;       // subset of lhc_gw_conv, lhc, lawnmower, hybrid
  std::vector<std::string> coordination;  // timed and/or paper (paper rows: CONFIG+paper)
  int rovers = 5;
  int targets = 64;
  unsigned missionThreads = 1;
};
const std::vector<std::string>& presetNames();
// Throws rover::Error (NotFound, field "preset") for an unknown name, InvalidParameter for a bad
// option (fields "configs", "coordination").
nlohmann::json presetSpecJson(const std::string& name, const PresetOptions& options = {});
StudySpec presetSpec(const std::string& name, int runs = 0);

}  // namespace rover::studies
