#include "core/team/formation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/common/error.hpp"
#include "core/planning/departure.hpp"
#include "core/planning/mission_check.hpp"
#include "core/planning/rover_limits.hpp"
#include "core/team/coordination.hpp"
#include "core/team/traversal_lattice.hpp"

namespace rover::team {

std::vector<Eigen::Vector2d> formationSlots(int rovers, double footprint) {
  if (rovers < 1) return {};
  const int m = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(rovers)) - 1e-9));
  const double spacing = footprint / m;
  std::vector<Eigen::Vector2d> lattice;
  for (int r = 0; r < m; ++r)
    for (int c = 0; c < m; ++c)
      lattice.emplace_back((c - (m - 1) / 2.0) * spacing, ((m - 1) / 2.0 - r) * spacing);
  // Farthest-point order from the point nearest the centre; ties to the earlier lattice point.
  std::vector<Eigen::Vector2d> out;
  std::vector<bool> used(lattice.size(), false);
  std::size_t first = 0;
  for (std::size_t i = 1; i < lattice.size(); ++i)
    if (lattice[i].norm() < lattice[first].norm() - 1e-12) first = i;
  out.push_back(lattice[first]);
  used[first] = true;
  while (static_cast<int>(out.size()) < rovers) {
    std::size_t best = 0;
    double bestD = -1;
    for (std::size_t i = 0; i < lattice.size(); ++i) {
      if (used[i]) continue;
      double d = std::numeric_limits<double>::infinity();
      for (const auto& o : out) d = std::min(d, (lattice[i] - o).norm());
      if (d > bestD + 1e-12) {
        bestD = d;
        best = i;
      }
    }
    used[best] = true;
    out.push_back(lattice[best]);
  }
  return out;
}

namespace {

// `slots` scaled about the centre until the nearest two are `spacing` apart (unchanged when they
// are already).
std::vector<Eigen::Vector2d> spread(std::vector<Eigen::Vector2d> slots, double spacing) {
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < slots.size(); ++a)
    for (std::size_t b = a + 1; b < slots.size(); ++b) nearest = std::min(nearest, (slots[a] - slots[b]).norm());
  if (nearest < spacing)
    for (auto& s : slots) s *= spacing / nearest;
  return slots;
}

// A window of the map (the cells over [lo, hi], clipped to it) as a map of its own: heights,
// per-row cell widths and classes, and where its local frame's origin lies in the map's.
struct GroundWindow {
  terrain::Dem dem;
  Raster<std::uint8_t> classes;
  Eigen::Vector2d offset{0, 0};
};

GroundWindow groundWindow(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                          const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  const GridGeometry& g = dem.geometry();
  auto index = [](double v, double cell, int count) {
    return static_cast<int>(std::clamp(std::floor(v / cell), 0.0, static_cast<double>(count - 1)));
  };
  // Rows count from the north edge.
  const int c0 = index(lo.x(), g.cellWidth, g.cols), c1 = index(hi.x(), g.cellWidth, g.cols);
  const int r0 = g.rows - 1 - index(hi.y(), g.cellHeight, g.rows);
  const int r1 = g.rows - 1 - index(lo.y(), g.cellHeight, g.rows);
  const GridGeometry w{r1 - r0 + 1, c1 - c0 + 1, g.cellWidth, g.cellHeight};
  GroundWindow out;
  out.dem.z = Raster<float>(w, 0.0f);
  out.classes = Raster<std::uint8_t>(w, 0);
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) {
      out.dem.z(r - r0, c - c0) = dem.z(r, c);
      out.classes(r - r0, c - c0) = classes(r, c);
    }
  if (!dem.rowCellWidth.empty())
    out.dem.rowCellWidth.assign(dem.rowCellWidth.begin() + r0, dem.rowCellWidth.begin() + r1 + 1);
  out.offset = {c0 * g.cellWidth, (g.rows - 1 - r1) * g.cellHeight};
  return out;
}

// How far past the farthest point a start may move to the ground window reaches: connected ground
// the rovers can only join by a detour longer than that counts as cut off (the start then moves
// on), which keeps the lattice's cost to the formation's surroundings on any map.
constexpr double kGroundMargin = 10.0;  // m

}  // namespace

std::vector<Eigen::Vector2d> startSlots(int rovers, double footprint, double safety) {
  return spread(formationSlots(rovers, footprint), startSpacing(safety));
}

std::vector<Eigen::Vector2d> goalSlots(int rovers, double footprint, double spacing) {
  return spread(formationSlots(rovers, footprint), spacing);
}

double laneTurn(int rovers, double heading) {
  const int m = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(std::max(rovers, 1))) - 1e-9));
  if (m < 2) return 0.0;
  const double quarter = M_PI / 2, ref = M_PI / 8, tilt = std::atan(1.0 / m);
  // The representative of `a` modulo a quarter turn in [ref - 45°, ref + 45°).
  const auto near = [&](double a) { return a - quarter * std::floor((a - (ref - quarter / 2)) / quarter); };
  const double plus = near(heading + tilt), minus = near(heading - tilt);
  return std::abs(plus - ref) <= std::abs(minus - ref) ? plus : minus;
}

std::vector<Eigen::Vector2d> turnedSlots(const std::vector<Eigen::Vector2d>& slots, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  std::vector<Eigen::Vector2d> out;
  out.reserve(slots.size());
  for (const auto& p : slots) out.emplace_back(c * p.x() - s * p.y(), s * p.x() + c * p.y());
  return out;
}

std::vector<Eigen::Vector2d> LaneHeading::slotsAt(const std::vector<Eigen::Vector2d>& slots,
                                                  const Eigen::Vector2d& centre) {
  const Eigen::Vector2d step = centre - last_;
  if (step.norm() > 1e-9) heading_ = std::atan2(step.y(), step.x());
  last_ = centre;
  return turnedSlots(slots, laneTurn(static_cast<int>(slots.size()), heading_));
}

TerrainEdgeModel wholeMapModel(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                               const RrtParams& rrt) {
  const GridGeometry& g = dem.geometry();
  return TerrainEdgeModel(dem, classes, mapBounds(g), rrt.attitudeLimit, edgeResolutionOn(g, rrt));
}

bool turnableAround(const TerrainEdgeModel& model, const Eigen::Vector2d& p, double radius) {
  if (!model.turnValid(p)) return false;
  if (radius > 0)
    for (int i = 0; i < 8; ++i) {
      const double a = i * M_PI / 4;
      if (!model.turnValid(p + radius * Eigen::Vector2d(std::cos(a), std::sin(a)))) return false;
    }
  return true;
}

std::optional<Eigen::Vector2d> nearestValid(const TerrainEdgeModel& model, Eigen::Vector2d want,
                                            double reach, double safety,
                                            const std::vector<Eigen::Vector2d>& taken,
                                            const Raster<std::uint8_t>* reachable,
                                            double stopRadius,
                                            const std::function<bool(const Eigen::Vector2d&)>& accept) {
  auto ok = [&](const Eigen::Vector2d& p) {
    if (!turnableAround(model, p, stopRadius)) return false;
    if (reachable) {
      auto c = localToCell(reachable->geometry, p);
      if (!c || (*reachable)(c->row, c->col) == 0) return false;
    }
    for (const auto& t : taken)
      if ((t - p).norm() < safety) return false;
    return !accept || accept(p);
  };
  if (ok(want)) return want;
  const double step = 0.25;
  for (double r = step; r <= reach + 1e-9; r += step) {
    const int n = std::max(8, static_cast<int>(std::ceil(2 * M_PI * r / step)));
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      const Eigen::Vector2d p = want + r * Eigen::Vector2d(std::cos(a), std::sin(a));
      if (ok(p)) return p;
    }
  }
  return std::nullopt;
}

std::vector<Pose> formationStarts(const terrain::Dem& dem, const TeamMissionParams& params,
                                  const Eigen::Vector2d& centre, int n) {
  params.validate();
  planning::checkRoverCount(static_cast<std::size_t>(std::max(n, 0)));
  const terrain::Traversability trav = terrain::traversability(dem, params.traversability);
  return formationStarts(dem, trav.classes, params, centre, n);
}

std::vector<Pose> formationStarts(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                  const TeamMissionParams& params, const Eigen::Vector2d& centre,
                                  int n) {
  params.validate();
  planning::checkRoverCount(static_cast<std::size_t>(std::max(n, 0)));
  const TerrainEdgeModel model = wholeMapModel(dem, classes, params.coordination.rrt);
  std::vector<Pose> out;
  std::vector<Eigen::Vector2d> taken;
  const double safety = params.coordination.safetyDistance, spacing = startSpacing(safety);
  // On open ground the lattice always leaves from the outside in; what can still shut a rover in
  // is the ground: a slot in a pocket of passable ground (on the default map 40 rovers put rover 4
  // in one, and the mission check refused the generated formation).
  const planning::PassableGround passable = planning::passableGround(dem, &classes);
  // And ground the rover's own validity rules do not connect to its team mates': the pocket test
  // reads the classes alone, and a slope the classes call passable can still be steeper than the
  // attitude limit along every move out. On the Kepler site 4 of 40 rovers stood on such a
  // shelf: the mission's goals lie on the ground any start reaches, so theirs were on the crater
  // floor they could never get to, and every one of their legs ended short. Every start after
  // the first is held to the ground the first one reaches on the mission's own lattice (the
  // traversal lattice's flood, the one source of "connected ground": what the mission computes
  // its reachable ground with), built on a window round the formation (kGroundMargin past the
  // farthest a start may move). formationStarts' CPU on the 600² default map and Kepler site, one
  // thread, 5 to 64 rovers: 0.03 to 0.13 s (0.005 to 0.08 s without this test; 0.35 to 0.6 s with
  // the whole map's lattice), against 5 to 15 s for their missions; memory 9 bytes a window cell,
  // whatever the map's size.
  const std::vector<Eigen::Vector2d> slots = startSlots(n, params.footprint, safety);
  const double reach = std::max(params.footprint, spacing);
  Eigen::Vector2d lo = centre, hi = centre;
  for (const auto& s : slots) {
    lo = lo.cwiseMin(centre + s);
    hi = hi.cwiseMax(centre + s);
  }
  const GroundWindow window = groundWindow(dem, classes, lo.array() - (reach + kGroundMargin),
                                           hi.array() + (reach + kGroundMargin));
  const TraversalLattice lattice = makeLattice(window.dem, window.classes, params.coordination);
  std::optional<Raster<std::uint8_t>> firstGround;
  auto acceptable = [&](const Eigen::Vector2d& p) {
    if (firstGround && !lattice.startsWithin(*firstGround, p - window.offset)) return false;
    return planning::departureOrder({p}, safety, passable).boxedIn.empty();
  };
  for (const auto& slot : slots) {
    auto p = nearestValid(model, centre + slot, reach, spacing, taken, nullptr, 0, acceptable);
    if (!p)
      throw Error(ErrorCode::InvalidInput, "rovers",
                  "no room for the rovers' formation near the start: give the starts explicitly");
    if (!firstGround) firstGround = lattice.reachable({*p - window.offset});
    taken.push_back(*p);
    out.push_back({p->x(), p->y(), 0.0});
  }
  return out;
}

}  // namespace rover::team
