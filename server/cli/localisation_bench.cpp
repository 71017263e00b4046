// `roverplan bench localisation` (issue 15): how much of the field a myopic coverage rover truly
// covers when its own map says it has covered the goal, against its localisation error — paper 000
// (Santra et al.) Table I: 95 % in simulation, 80 % (clayey soil, MAE 0.41 m) and 65 % (sandy soil,
// MAE 0.32 m) in the field, with loop closure "significantly" helping. Seeded sweeps over noise
// levels, with and without loop closure, on paper 000's 5 × 5 m field and its 60 × 60 m simulation
// (1 m cells, CLOVER's energy model: the coverage defaults).
#include <algorithm>
#include <iomanip>
#include <sstream>

#include "core/common/parallel.hpp"
#include "core/coverage/coverage_planner.hpp"
#include "server/cli/commands.hpp"
#include "server/cli/localisation_bench.hpp"

namespace rover::cli {

namespace {

struct LevelFigures {
  double mae = 0, maxError = 0, trueCoverage = 0, believedCoverage = 0, bumps = 0, loops = 0;
  double trueAtGoal = 0;  // mean true coverage of the runs whose believed map reached the goal
  int atGoal = 0, runs = 0;
};

LevelFigures runLevel(int size, double obstacles, double odometryPct, double headingDeg,
                      double slipPerDeg, bool loopClosure, std::int64_t gap, int runs,
                      unsigned threads) {
  struct One {
    double mae, maxError, trueCov, believedCov, bumps, loops;
    bool atGoal;
  };
  std::vector<One> out(runs);
  parallelFor(runs, threads, [&](std::size_t i) {
    coverage::WorldParams wp;
    wp.rows = wp.cols = size;
    wp.obstacleFraction = obstacles;
    wp.seed = i + 1;
    const coverage::World world = coverage::generateWorld(wp);
    coverage::CoverageParams p;
    p.localisation.distanceNoisePct = odometryPct;
    p.localisation.headingNoiseDeg = headingDeg;
    p.localisation.slipPctPerDeg = slipPerDeg;
    p.localisation.loopClosure = loopClosure;
    p.localisation.loopClosureGap = gap;
    p.localisation.seed = i + 1;
    // Engaged even at zero noise, so the zero row reports its (zero) error like the others.
    if (!p.localisation.active()) p.localisation.loopClosure = true;
    const auto r = coverage::runCoverage(world, coverage::randomStarts(world, 1, wp.seed), p);
    const auto& m = r.metrics;
    out[i] = {m.maeM, m.maxErrorM, m.trueCoverage, m.coverage, static_cast<double>(m.bumps),
              static_cast<double>(m.loopClosures), r.stop == coverage::StopReason::GoalReached};
  });
  LevelFigures f;
  f.runs = runs;
  for (const One& o : out) {
    f.mae += o.mae / runs;
    f.maxError += o.maxError / runs;
    f.trueCoverage += o.trueCov / runs;
    f.believedCoverage += o.believedCov / runs;
    f.bumps += o.bumps / runs;
    f.loops += o.loops / runs;
    if (o.atGoal) ++f.atGoal, f.trueAtGoal += o.trueCov;
  }
  if (f.atGoal) f.trueAtGoal /= f.atGoal;
  return f;
}

std::vector<double> parseList(const std::string& text, const char* option) {
  std::vector<double> v;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) {
    char* end = nullptr;
    const double d = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !(d >= 0) || d > 100)
      throw UsageError(std::string("invalid value for --") + option + ": '" + item + "'");
    v.push_back(d);
  }
  if (v.empty() || v.size() > 64) throw UsageError(std::string("invalid value for --") + option);
  return v;
}

}  // namespace

void addLocalisationBenchOptions(ArgParser& args) {
  args.option("sizes", "N,N", "5,60", "bench localisation: square fields, cells of 1 m.");
  args.option("levels", "S,S,...", "0,0.25,0.5,1,1.5,2,3,4",
              "bench localisation: noise levels S: odometry_noise = 4·S %, heading_noise = S deg.");
  args.option("slip", "X", "0", "bench localisation: slip_per_deg at every level [%/deg].");
  args.option("gap", "N", "20", "bench localisation: loop_closure_gap [moves].");
  args.option("threads", "N", "1", "bench localisation: threads.");
}

int benchLocalisation(const ArgParser& args, int runs, std::ostream& out) {
  const std::vector<double> sizes = parseList(args.str("sizes", "5,60"), "sizes");
  const std::vector<double> levels = parseList(args.str("levels", ""), "levels");
  const double slip = args.real("slip", 0, 0, 10);
  const std::int64_t gap = args.integer("gap", 20, 1, 1000000000);
  const unsigned threads = static_cast<unsigned>(args.integer("threads", 1, 1, 256));
  out << "bench localisation: spiral to 95 % believed coverage, 5 % obstacles, 1 m cells, " << runs
      << " seeded runs per line (world, start and noise seeds 1.." << runs << "); slip "
      << slip << " %/deg, loop_closure_gap " << gap << " moves\n";
  out << "paper 000 Table I (field, 5 x 5 m): clayey soil 80 % coverage at MAE 0.41 m, sandy soil "
         "65 % at MAE 0.32 m; 95 % in simulation\n";
  for (double sizeD : sizes) {
    const int size = static_cast<int>(sizeD);
    if (size < 3 || size > 200) throw UsageError("invalid value for --sizes: 3 to 200 cells a side");
    out << "\nfield " << size << " x " << size << " m\n";
    out << std::left << std::setw(7) << "level" << std::setw(8) << "odo %" << std::setw(8)
        << "head °" << std::setw(6) << "loop" << std::right << std::setw(8) << "MAE m"
        << std::setw(8) << "max m" << std::setw(9) << "believed" << std::setw(8) << "true"
        << std::setw(9) << "at goal" << std::setw(13) << "true @ goal" << std::setw(8) << "bumps"
        << std::setw(8) << "loops" << "\n";
    for (double s : levels) {
      for (bool loop : {false, true}) {
        const LevelFigures f = runLevel(size, 0.05, 4 * s, s, slip, loop, gap, runs, threads);
        out << std::left << std::fixed << std::setprecision(3) << std::setw(7) << s
            << std::setw(8) << 4 * s << std::setw(8) << s << std::setw(6) << (loop ? "on" : "off")
            << std::right << std::setprecision(3) << std::setw(8) << f.mae << std::setw(8)
            << f.maxError << std::setprecision(1) << std::setw(8) << f.believedCoverage * 100 << "%"
            << std::setw(7) << f.trueCoverage * 100 << "%" << std::setw(8)
            << 100.0 * f.atGoal / f.runs << "%";
        if (f.atGoal)
          out << std::setw(12) << f.trueAtGoal * 100 << "%";
        else
          out << std::setw(13) << "-";
        out << std::setprecision(1) << std::setw(8) << f.bumps << std::setw(8) << f.loops << "\n";
      }
    }
  }
  return 0;
}

}  // namespace rover::cli
