#include "core/team/terrain_rrt.hpp"

#include <ompl/base/MotionValidator.h>
#include <ompl/base/OptimizationObjective.h>
#include <ompl/base/PlannerData.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>
#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include "core/common/error.hpp"
#include "core/common/random.hpp"
#include "core/team/grid_neighbors.hpp"
#include "core/terrain/layers.hpp"

namespace rover::team {

namespace ob = ompl::base;
namespace og = ompl::geometric;

// ---------------------------------------------------------------------------------------------
// Parameters

namespace {

void requireFinite(const char* key, double v) {
  if (!std::isfinite(v)) throwInvalidParameter(key, "must be a finite number");
}
void requireNonNegative(const char* key, double v) {
  if (!std::isfinite(v) || !(v >= 0)) throwInvalidParameter(key, "must be a finite number >= 0");
}
void requirePositive(const char* key, double v) {
  if (!std::isfinite(v) || !(v > 0)) throwInvalidParameter(key, "must be a finite number > 0");
}

}  // namespace

void TerrainCostWeights::validate() const {
  requireNonNegative("w_r", wR);
  requireNonNegative("w_phi", wPhi);
  requireNonNegative("w_theta", wTheta);
  requireNonNegative("w_psi", wPsi);
  requirePositive("n_r", nR);
  requirePositive("n_phi", nPhi);
  requirePositive("n_theta", nTheta);
  requirePositive("n_psi", nPsi);
}

void RrtParams::validate() const {
  requirePositive("range", range);
  if (maxVertices < 2) throwInvalidParameter("max_vertices", "must be an integer >= 2");
  // A zero clearance would give a degenerate (zero-area) box when start and goal share an axis.
  requirePositive("clearance", clearance);
  requirePositive("attitude_limit", attitudeLimit);
  if (attitudeLimit > std::numbers::pi / 2)
    throwInvalidParameter("attitude_limit", "must be <= 90°");
  requireNonNegative("edge_resolution", edgeResolution);
  requireFinite("goal_bias", goalBias);
  if (goalBias < 0 || goalBias > 1) throwInvalidParameter("goal_bias", "must be in [0, 1]");
  if (maxIterations < 1) throwInvalidParameter("max_iterations", "must be an integer >= 1");
}

// ---------------------------------------------------------------------------------------------
// Geometry and the eq. 9 terms (no OMPL)

SearchBounds searchBounds(const GridGeometry& map, const Eigen::Vector2d& start,
                          const Eigen::Vector2d& goal, double clearance) {
  const Eigen::Vector2d extent(map.widthMetres(), map.heightMetres());
  SearchBounds b;
  b.min = (start.cwiseMin(goal).array() - clearance).max(0.0).matrix();
  b.max = (start.cwiseMax(goal).array() + clearance).min(extent.array()).matrix();
  return b;
}

SearchBounds mapBounds(const GridGeometry& map) {
  return {{0, 0}, {map.widthMetres(), map.heightMetres()}};
}

double edgeResolutionOn(const GridGeometry& map, const RrtParams& params) {
  return params.edgeResolution > 0 ? params.edgeResolution
                                   : 0.25 * std::min(map.cellWidth, map.cellHeight);
}

double headingChange(double from, double to) {
  double d = std::remainder(to - from, 2 * std::numbers::pi);  // in [−π, π]
  return std::abs(d);
}

TerrainEdgeModel::TerrainEdgeModel(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                   SearchBounds bounds, double attitudeLimit, double edgeResolution)
    : dem_(dem),
      classes_(classes),
      bounds_(bounds),
      limit_(attitudeLimit),
      resolution_(edgeResolution) {
  const GridGeometry &d = dem.geometry(), &c = classes.geometry;
  if (d.rows != c.rows || d.cols != c.cols)
    throw Error(ErrorCode::InvalidInput, "classes",
                "traversability classes (" + std::to_string(c.rows) + "×" + std::to_string(c.cols) +
                    ") do not match the DEM (" + std::to_string(d.rows) + "×" +
                    std::to_string(d.cols) + ")");
  if (!(edgeResolution > 0) || !std::isfinite(edgeResolution))
    throwInvalidParameter("edge_resolution", "must be a finite number > 0");
}

namespace {

// Cell checks shared by pointValid and edgeValid: inside the bounds and the map, data present, not
// impassable, not in an operator's zone. High-risk cells are allowed; the attitude limit decides
// along edges. The cell, when allowed (the corridor reads it too: one lookup per sample).
std::optional<CellIndex> allowedCell(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                                     const SearchBounds& bounds, const Eigen::Vector2d& p) {
  if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !bounds.contains(p)) return std::nullopt;
  auto cell = localToCell(classes.geometry, p);
  if (!cell) return std::nullopt;
  auto cls = static_cast<terrain::TerrainClass>(classes(cell->row, cell->col));
  if (cls == terrain::TerrainClass::Impassable || cls == terrain::TerrainClass::NoData ||
      cls == terrain::TerrainClass::KeepOut)
    return std::nullopt;
  if (!dem.valid(cell->row, cell->col)) return std::nullopt;
  return cell;
}

// Number of segments an edge of length `len` is cut into for sampling.
int segmentsFor(double len, double resolution) {
  return std::max(1, static_cast<int>(std::ceil(len / resolution)));
}

Eigen::Vector2d sampleAt(const Eigen::Vector2d& a, const Eigen::Vector2d& b, int i, int n) {
  return i == n ? b : Eigen::Vector2d(a + (b - a) * (static_cast<double>(i) / n));
}

}  // namespace

// Outside every keep-out disc, off the operator's keep-out zones' cells (the class KeepOut: never
// waived, not even in the escape disc), and inside the corridor when there is one.
bool TerrainEdgeModel::outsideKeepOut(const Eigen::Vector2d& p) const {
  if (corridor_ && !corridor_->contains(p)) return false;
  if (inZone(p)) return false;
  return outsideDiscs(p);
}

bool TerrainEdgeModel::outsideDiscs(const Eigen::Vector2d& p) const {
  for (const auto& z : keepOut_)
    if ((p - z.centre).squaredNorm() <= z.radius * z.radius) return false;
  return true;
}

// allowedCell, then the corridor and the discs: outsideKeepOut on an allowed cell (its zone check
// is allowedCell's class check), with the cell looked up once.
bool TerrainEdgeModel::allowed(const Eigen::Vector2d& p) const {
  const auto cell = allowedCell(dem_, classes_, bounds_, p);
  if (!cell) return false;
  if (corridor_ && !corridor_->containsCell(*cell)) return false;
  return outsideDiscs(p);
}

bool TerrainEdgeModel::pointValid(const Eigen::Vector2d& p) const {
  terrain::SurfacePoint sp;
  if (inEscape(p))
    return bounds_.contains(p) && outsideKeepOut(p) && terrain::bilinearSurfaceAt<false>(dem_, p.x(), p.y(), sp);
  return allowed(p) && terrain::bilinearSurfaceAt<false>(dem_, p.x(), p.y(), sp);
}

bool TerrainEdgeModel::turnValid(const Eigen::Vector2d& p) const {
  if (inEscape(p)) return pointValid(p);
  if (!allowed(p)) return false;
  terrain::SurfacePoint sp;
  const double t = std::tan(limit_);
  return terrain::bilinearSurfaceAt<false>(dem_, p.x(), p.y(), sp) &&
         sp.dzdx * sp.dzdx + sp.dzdy * sp.dzdy < t * t;
}

// Roll and pitch follow SPEC §2 exactly as terrain::attitudeAt does — pitch = atan(∇h·(cosψ,
// sinψ)), roll = atan(∇h·(−sinψ, cosψ)) on the bilinear surface — but with the edge's cos ψ, sin ψ
// computed once and atan applied once to the largest tangent (atan is monotonic, so max|atan x| =
// atan max|x|, and |atan x| >= limit <=> |x| >= tan limit). Calling attitudeAt per sample costs
// two atan and a sincos each and made up most of a planning call; a test checks the two agree.
bool TerrainEdgeModel::edgeValid(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  const Eigen::Vector2d d = b - a;
  const double len = d.norm();
  if (!(len > 0)) return pointValid(a);  // no heading: only the point itself
  const double c = d.x() / len, s = d.y() / len, tanLimit = std::tan(limit_);
  const int n = segmentsFor(len, resolution_);
  terrain::SurfacePoint sp;
  for (int i = 0; i <= n; ++i) {
    const Eigen::Vector2d p = sampleAt(a, b, i, n);
    if (inEscape(p)) {
      if (!pointValid(p)) return false;
      continue;
    }
    if (!allowed(p) || !terrain::bilinearSurfaceAt<false>(dem_, p.x(), p.y(), sp)) return false;
    if (std::abs(sp.dzdx * c + sp.dzdy * s) >= tanLimit ||
        std::abs(-sp.dzdx * s + sp.dzdy * c) >= tanLimit)
      return false;
  }
  return true;
}

// φ and θ are the *largest* |roll| and |pitch| over the edge's samples, not their mean: eq. 9's N_φ
// and N_θ are "the maximum valid value" (paper 001 §3.6), i.e. the same 15° limit that edgeValid
// applies sample by sample, so with the maximum every valid edge has φ/N_φ, θ/N_θ in [0, 1), and an
// edge that grazes a steep spot pays for it even if the rest is flat. Like the paper's per-node
// cost, the attitude terms are per edge, not per metre.
EdgeTerms TerrainEdgeModel::edgeTerms(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  EdgeTerms t;
  const Eigen::Vector2d d = b - a;
  t.length = d.norm();
  if (!(t.length > 0)) return t;
  const double c = d.x() / t.length, s = d.y() / t.length;
  double tanPitch = 0, tanRoll = 0;  // largest |∇h·(cosψ, sinψ)|, |∇h·(−sinψ, cosψ)|
  if (!patch_ || !patchTangents(a, b, c, s, tanPitch, tanRoll)) {
    const int n = segmentsFor(t.length, resolution_);
    terrain::SurfacePoint sp;
    for (int i = 0; i <= n; ++i) {
      const Eigen::Vector2d p = sampleAt(a, b, i, n);
      if (terrain::bilinearSurfaceAt<false>(dem_, p.x(), p.y(), sp)) {
        tanPitch = std::max(tanPitch, std::abs(sp.dzdx * c + sp.dzdy * s));
        tanRoll = std::max(tanRoll, std::abs(-sp.dzdx * s + sp.dzdy * c));
      }
    }
  }
  t.pitch = std::atan(tanPitch);
  t.roll = std::atan(tanRoll);
  return t;
}

namespace {

// The crossings of one pixel coordinate (u or v of terrain::bilinearSurfaceAt) with the lines
// 0 … hi (rows or columns of cell centres) as an edge is driven: the coordinate is x0 + t·d for t
// in [0, 1], so the crossings are evenly spaced in t. Outside [0, hi] the surface clamps the
// coordinate (the border's half cells), so 0 and hi are crossings too and nothing beyond them is.
class CentreCrossings {
 public:
  CentreCrossings(double x0, double d, double hi) {
    double first = 0, last = -1;  // the lines crossed strictly inside (0, 1), in driving order
    if (d > 0) {
      first = std::max(std::floor(x0) + 1, 0.0);
      last = std::min(std::ceil(x0 + d) - 1, hi);
    } else if (d < 0) {
      first = std::min(std::ceil(x0) - 1, hi);
      last = std::max(std::floor(x0 + d) + 1, 0.0);
    }
    const double count = d > 0 ? last - first + 1 : d < 0 ? first - last + 1 : 0;
    if (count > 0) {
      left_ = static_cast<long>(count);
      t_ = (first - x0) / d;
      step_ = 1.0 / std::abs(d);
    }
  }
  // The t of the next crossing; 2 when there is none before the edge's end.
  double next() const { return left_ > 0 ? t_ : 2.0; }
  void advance() {
    --left_;
    t_ += step_;
  }

 private:
  double t_ = 2.0, step_ = 0;
  long left_ = 0;
};

}  // namespace

bool TerrainEdgeModel::patchTangents(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double c,
                                     double s, double& tanPitch, double& tanRoll) const {
  const GridGeometry& g = dem_.geometry();
  if (g.rows < 2 || g.cols < 2) return false;
  const bool perRow = !dem_.rowCellWidth.empty();
  const auto onMap = [&](const Eigen::Vector2d& p) {
    return p.x() >= 0 && p.y() >= 0 && p.x() <= g.widthMetres() && p.y() <= g.heightMetres();
  };
  if (!a.allFinite() || !b.allFinite() || !onMap(a) || !onMap(b)) return false;
  // Pixel coordinates as bilinearSurfaceAt computes them, affine in t.
  const double uHi = g.cols - 1.0, vHi = g.rows - 1.0;
  const double u0 = a.x() / g.cellWidth - 0.5, du = (b.x() - a.x()) / g.cellWidth;
  const double v0 = (g.rows - a.y() / g.cellHeight) - 0.5, dv = -(b.y() - a.y()) / g.cellHeight;
  const auto uAt = [&](double t) { return std::clamp(u0 + t * du, 0.0, uHi); };
  const auto vAt = [&](double t) { return std::clamp(v0 + t * dv, 0.0, vHi); };
  // With per-row cell widths (geographic grids) the width bilinearSurfaceAt divides by is the
  // nearest row's: it changes halfway between rows of centres, so those lines cut pieces too.
  CentreCrossings cu(u0, du, uHi), cv(v0, dv, vHi), cw(v0 - 0.5, perRow ? dv : 0.0, g.rows - 2.0);
  double maxPitch = tanPitch, maxRoll = tanRoll;
  const double invDy = 1.0 / dem_.dy();
  for (double t0 = 0; t0 < 1;) {
    const double nu = cu.next(), nv = cv.next(), nw = cw.next();
    const double t1 = std::min(std::min(nu, nv), std::min(nw, 1.0));
    if (nu == t1) cu.advance();
    if (nv == t1) cv.advance();
    if (nw == t1) cw.advance();
    // The piece [t0, t1] lies in one patch: the one its middle is in (as bilinearSurfaceAt picks
    // it). Its gradient, on the patch's own formula, at both ends: ∂z/∂x = ex + fv·fx and
    // ∂z/∂y = ey + fu·fy with fu, fv the position in the patch.
    const double tm = 0.5 * (t0 + t1), um = uAt(tm), vm = vAt(tm);
    const int c0 = std::min(static_cast<int>(um), g.cols - 2);
    const int r0 = std::min(static_cast<int>(vm), g.rows - 2);
    const double z00 = dem_.z(r0, c0), z01 = dem_.z(r0, c0 + 1), z10 = dem_.z(r0 + 1, c0),
                 z11 = dem_.z(r0 + 1, c0 + 1);
    if (!std::isnan(z00 + z01 + z10 + z11)) {  // no surface: skipped, as a sample would be
      // vm >= 0: rounding half up is std::lround's rounding.
      const double invW = 1.0 / (perRow ? dem_.dx(std::min(static_cast<int>(vm + 0.5), g.rows - 1)) : g.cellWidth);
      const double ex = (z01 - z00) * invW, fx = (z11 - z10 - z01 + z00) * invW;
      const double ey = -(z10 - z00) * invDy, fy = -(z11 - z01 - z10 + z00) * invDy;
      for (const double t : {t0, t1}) {
        const double fu = std::clamp(uAt(t) - c0, 0.0, 1.0), fv = std::clamp(vAt(t) - r0, 0.0, 1.0);
        const double dzdx = ex + fv * fx, dzdy = ey + fu * fy;
        maxPitch = std::max(maxPitch, std::abs(dzdx * c + dzdy * s));
        maxRoll = std::max(maxRoll, std::abs(-dzdx * s + dzdy * c));
      }
    }
    t0 = t1;
  }
  tanPitch = maxPitch;
  tanRoll = maxRoll;
  return true;
}

std::optional<EdgeTerms> TerrainEdgeModel::validEdgeTerms(const Eigen::Vector2d& a,
                                                          const Eigen::Vector2d& b) const {
  EdgeTerms t;
  const Eigen::Vector2d d = b - a;
  t.length = d.norm();
  if (!(t.length > 0) || escapeRadius_ > 0) {  // the general path (escape discs, no heading)
    if (!edgeValid(a, b)) return std::nullopt;
    return edgeTerms(a, b);
  }
  const double c = d.x() / t.length, s = d.y() / t.length, tanLimit = std::tan(limit_);
  const int n = segmentsFor(t.length, resolution_);
  double tanPitch = 0, tanRoll = 0;
  terrain::SurfacePoint sp;
  for (int i = 0; i <= n; ++i) {
    const Eigen::Vector2d p = sampleAt(a, b, i, n);
    if (!allowed(p) || !terrain::bilinearSurfaceAt<false>(dem_, p.x(), p.y(), sp)) return std::nullopt;
    const double pitch = std::abs(sp.dzdx * c + sp.dzdy * s);
    const double roll = std::abs(-sp.dzdx * s + sp.dzdy * c);
    if (pitch >= tanLimit || roll >= tanLimit) return std::nullopt;
    tanPitch = std::max(tanPitch, pitch);
    tanRoll = std::max(tanRoll, roll);
  }
  t.pitch = std::atan(tanPitch);
  t.roll = std::atan(tanRoll);
  return t;
}

EdgeTerms TerrainEdgeModel::edgeTerms(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                      double previousHeading) const {
  EdgeTerms t = edgeTerms(a, b);
  if (t.length > 0)
    t.headingChange = headingChange(previousHeading, std::atan2(b.y() - a.y(), b.x() - a.x()));
  return t;
}

double pathCost(const TerrainEdgeModel& model, const std::vector<Eigen::Vector2d>& path,
                double startHeading, const TerrainCostWeights& weights, bool turnsAtEveryVertex) {
  double sum = 0, heading = startHeading;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::Vector2d &a = path[i], &b = path[i + 1];
    EdgeTerms t =
        (i == 0 || turnsAtEveryVertex) ? model.edgeTerms(a, b, heading) : model.edgeTerms(a, b);
    sum += t.cost(weights);
    if (t.length > 0) heading = std::atan2(b.y() - a.y(), b.x() - a.x());
  }
  return sum;
}

bool TerrainEdgeModel::inZone(const Eigen::Vector2d& p) const {
  auto cell = localToCell(classes_.geometry, p);
  return cell && classes_(cell->row, cell->col) == static_cast<std::uint8_t>(terrain::TerrainClass::KeepOut);
}

// ---------------------------------------------------------------------------------------------
// OMPL glue

namespace {

Eigen::Vector2d xyOf(const ob::State* s) {
  const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
  return {v->values[0], v->values[1]};
}

// core/ does no I/O: OMPL's console output is switched off once per process (a global setting in
// OMPL; done under std::call_once so concurrent first calls do not race on it).
void silenceOmpl() {
  static std::once_flag once;
  std::call_once(once, [] {
    ompl::msg::noOutputHandler();
    ompl::msg::setLogLevel(ompl::msg::LOG_NONE);
  });
}

// Tree vertices are where the rover turns in place: turnValid. The start is exempt (the rover is
// already there, possibly pushed by the simulation onto a steeper spot); it only has to be
// pointValid.
class TerrainValidityChecker : public ob::StateValidityChecker {
 public:
  TerrainValidityChecker(const ob::SpaceInformationPtr& si, const TerrainEdgeModel& model,
                         const Eigen::Vector2d& start)
      : ob::StateValidityChecker(si), model_(model), start_(start) {}
  bool isValid(const ob::State* s) const override {
    const Eigen::Vector2d p = xyOf(s);
    return p == start_ ? model_.pointValid(p) : model_.turnValid(p);
  }

 private:
  const TerrainEdgeModel& model_;
  Eigen::Vector2d start_;
};

class TerrainMotionValidator : public ob::MotionValidator {
 public:
  TerrainMotionValidator(const ob::SpaceInformationPtr& si, const TerrainEdgeModel& model)
      : ob::MotionValidator(si), model_(model) {}

  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    bool ok = model_.edgeValid(xyOf(s1), xyOf(s2));
    ++(ok ? valid_ : invalid_);
    return ok;
  }

  // Walks the same samples as edgeValid and reports the last valid one (RRTstar does not use this
  // overload; other OMPL tools may).
  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& lastValid) const override {
    const Eigen::Vector2d a = xyOf(s1), b = xyOf(s2);
    if (model_.edgeValid(a, b)) {
      ++valid_;
      return true;
    }
    const int n = segmentsFor((b - a).norm(), model_.edgeResolution());
    int last = 0;  // index of the last sample i such that the sub-edge a→sample(i) is valid
    for (int i = 1; i <= n; ++i) {
      if (!model_.edgeValid(a, sampleAt(a, b, i, n))) break;
      last = i;
    }
    const double t = static_cast<double>(last) / n;
    if (lastValid.first) si_->getStateSpace()->interpolate(s1, s2, t, lastValid.first);
    lastValid.second = t;
    ++invalid_;
    return false;
  }

 private:
  const TerrainEdgeModel& model_;
};

// Paper 001 eq. 9 as an OMPL optimisation objective, apart from the search (STYLE.md).
//
// Δψ in a geometric R² space: the turn from the previous edge is not available in motionCost(s1,
// s2) — a state (x, y) does not know which edge reached it — and making the cost depend on the
// parent's incoming edge would break RRT*'s rewiring (a rewired vertex changes its children's edge
// costs, which RRT* assumes fixed). An SE(2) space does not help either: OMPL's straight-line
// interpolation of (x, y, ψ) turns the body while it drives, so ψ no longer is the direction of
// travel; a Dubins space would tie them but impose a turning radius on a skid-steered rover that
// turns on the spot (paper 001 §2.3). We therefore keep R² and charge Δψ where it is known exactly:
// on edges leaving the start state, as the turn from the rover's start heading (its heading on
// arrival from the previous segment). Interior turns are free in the search; the R term and RRT*'s
// rewiring already keep paths close to straight, and PathResult::costWithTurns reports eq. 9 with
// every turn charged. The cost is then Markov in (s1, s2), and symmetric except on edges into the
// start, which RRT* never rewires (nothing beats the start's identity cost), so isSymmetric() stays
// true.
class Eq9Objective : public ob::OptimizationObjective {
 public:
  Eq9Objective(const ob::SpaceInformationPtr& si, const TerrainEdgeModel& model,
               const TerrainCostWeights& weights, const Eigen::Vector2d& start, double startHeading)
      : ob::OptimizationObjective(si),
        model_(model),
        weights_(weights),
        start_(start),
        startHeading_(startHeading) {
    description_ = "terrain cost, paper 001 eq. 9";
  }

  // Never satisfied: the tree always grows to the vertex budget (paper 001 §3.6).
  bool isSatisfied(ob::Cost) const override { return false; }
  ob::Cost stateCost(const ob::State*) const override { return identityCost(); }
  ob::Cost motionCost(const ob::State* s1, const ob::State* s2) const override {
    const Eigen::Vector2d a = xyOf(s1), b = xyOf(s2);
    // RRTstar copies the start state bit for bit, so exact comparison identifies it.
    EdgeTerms t = a == start_ ? model_.edgeTerms(a, b, startHeading_) : model_.edgeTerms(a, b);
    return ob::Cost(t.cost(weights_));
  }
  // Admissible: the R term alone (the other terms are >= 0).
  ob::Cost motionCostHeuristic(const ob::State* s1, const ob::State* s2) const override {
    return ob::Cost(weights_.wR * (xyOf(s2) - xyOf(s1)).norm() / weights_.nR);
  }

 private:
  const TerrainEdgeModel& model_;
  TerrainCostWeights weights_;
  Eigen::Vector2d start_;
  double startHeading_;
};

// Per-problem determinism. ompl::RNG::setSeed() fixes the seed of the *process-wide* generator of
// seeds and only works before the first RNG is created, so it cannot give each of several
// concurrent problems its own seed. Instead, every random stream RRT* draws from is re-seeded
// locally with RNG::setLocalSeed(): the planner's own rng_ (goal biasing; a protected member,
// reached from this subclass) and the uniform state sampler's rng_ (through a StateSamplerAllocator
// on the problem's state space, below). The only other RNG involved, inside the GNAT
// nearest-neighbour structure, picks pivots; GNAT's queries are exact, so it changes speed, not
// results.
class SeededRrtStar : public og::RRTstar {
 public:
  SeededRrtStar(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::RRTstar(si) {
    rng_.setLocalSeed(seed);
  }
  // Vertices currently in the tree (the termination condition polls this every iteration).
  std::size_t treeSize() const { return nn_ ? nn_->size() : 0; }
  // The exact grid neighbours over the search box instead of GNAT (grid_neighbors.hpp): the same
  // neighbours in the same order, for fewer distance calls. Before setup(), which keeps it.
  void useGridNeighbors(const SearchBounds& box, double cell) {
    nn_ = std::make_shared<GridNearestNeighbors<Motion*>>(
        box.min, box.max, cell, [](Motion* const& m) { return xyOf(m->state); });
  }
  bool usesGridNeighbors() const {
    return dynamic_cast<const GridNearestNeighbors<Motion*>*>(nn_.get()) != nullptr;
  }
};

class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, std::uint32_t seed)
      : ob::RealVectorStateSampler(space) {
    rng_.setLocalSeed(seed);
  }
};

}  // namespace

PathResult planPath(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                    const Eigen::Vector2d& start, double startHeading, const Eigen::Vector2d& goal,
                    const RrtParams& params, const TerrainCostWeights& weights,
                    const CancelToken* cancel, const std::vector<KeepOutZone>& keepOut,
                    const Corridor* corridor) {
  params.validate();
  weights.validate();
  requireFinite("start_heading", startHeading);
  if (!start.allFinite()) throwInvalidParameter("start", "must be a finite position");
  if (!goal.allFinite()) throwInvalidParameter("goal", "must be a finite position");
  silenceOmpl();

  const GridGeometry& g = dem.geometry();
  const double resolution = edgeResolutionOn(g, params);
  const SearchBounds box = corridor ? corridor->bounds : searchBounds(g, start, goal, params.clearance);
  TerrainEdgeModel model(dem, classes, box, params.attitudeLimit, resolution);
  model.setCorridor(corridor);
  for (const auto& z : keepOut)
    if (!z.centre.allFinite() || !std::isfinite(z.radius) || z.radius < 0)
      throwInvalidParameter("keep_out", "zones need a finite centre and a radius >= 0");
  model.setKeepOut(keepOut);
  model.setEvaluation(params.evaluation);

  PathResult r;
  if (!model.pointValid(start)) {
    // On the map with data but on impassable or steep ground: let the rover drive off.
    if (box.contains(start) && terrain::surfaceAt(dem, start.x(), start.y())) model.setEscape(start, 0.5);
    if (!model.pointValid(start)) {
      r.status = PathStatus::InvalidStart;
      return r;
    }
  }
  if (!model.turnValid(goal)) {
    r.status = PathStatus::InvalidGoal;
    return r;
  }
  if (cancel && cancel->cancelled()) {
    r.status = PathStatus::Cancelled;
    return r;
  }
  if (start == goal) {  // nothing to plan; OMPL would return a duplicated point
    r.status = PathStatus::Exact;
    r.waypoints = {start};
    r.vertices = 1;
    return r;
  }

  // Problem: R² inside the search box.
  auto space = std::make_shared<ob::RealVectorStateSpace>(2);
  ob::RealVectorBounds bounds(2);
  for (int i = 0; i < 2; ++i) {
    bounds.setLow(i, box.min[i]);
    bounds.setHigh(i, box.max[i]);
  }
  space->setBounds(bounds);
  const auto samplerSeed = static_cast<std::uint32_t>(deriveSeed(params.seed, 1));
  const auto plannerSeed = static_cast<std::uint32_t>(deriveSeed(params.seed, 2));
  space->setStateSamplerAllocator([samplerSeed](const ob::StateSpace* s) -> ob::StateSamplerPtr {
    return std::make_shared<SeededSampler>(s, samplerSeed);
  });

  auto si = std::make_shared<ob::SpaceInformation>(space);
  si->setStateValidityChecker(std::make_shared<TerrainValidityChecker>(si, model, start));
  si->setMotionValidator(std::make_shared<TerrainMotionValidator>(si, model));
  si->setup();

  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  ob::ScopedState<> s(space), q(space);
  s[0] = start.x();
  s[1] = start.y();
  q[0] = goal.x();
  q[1] = goal.y();
  pdef->setStartAndGoalStates(s, q);
  pdef->setOptimizationObjective(
      std::make_shared<Eq9Objective>(si, model, weights, start, startHeading));

  auto planner = std::make_shared<SeededRrtStar>(si, plannerSeed);
  planner->setRange(params.range);
  planner->setGoalBias(params.goalBias);
  // r-disc rewiring: OMPL caps the rewiring radius at the range, so no edge of the tree (new or
  // rewired) is longer than `range` — paper 001's N_R = 1 m assumes exactly that. k-nearest
  // rewiring has no such cap.
  planner->setKNearest(false);
  // Buckets of half the range, so an r-disc query (r <= range) reads at most 5 × 5 of them; at
  // most 128 a side (a corridor can span the map): 16 384 buckets, 400 kB.
  const Eigen::Vector2d extent = box.max - box.min;
  planner->useGridNeighbors(box, std::max(params.range / 2, extent.maxCoeff() / 128));
  planner->setProblemDefinition(pdef);
  planner->setup();
  if (!planner->usesGridNeighbors())
    throw std::logic_error("OMPL's RRTstar::setup replaced the nearest-neighbour structure");

  // Vertex-count termination (paper 001 §3.6), not wall-clock, so the result depends on the seed
  // only; the iteration cap and the cancel token are the other ways out.
  const auto maxVertices = static_cast<std::size_t>(params.maxVertices);
  const auto maxIterations = static_cast<unsigned>(params.maxIterations);
  ob::PlannerTerminationCondition ptc([&] {
    return planner->treeSize() >= maxVertices || planner->numIterations() >= maxIterations ||
           (cancel && cancel->cancelled());
  });
  const ob::PlannerStatus status = planner->solve(ptc);

  ob::PlannerData data(si);
  planner->getPlannerData(data);
  r.vertices = static_cast<int>(data.numVertices());
  r.iterations = static_cast<int>(planner->numIterations());

  if (cancel && cancel->cancelled()) {
    r.status = PathStatus::Cancelled;
    return r;
  }
  switch (ob::PlannerStatus::StatusType(status)) {
    case ob::PlannerStatus::EXACT_SOLUTION:
      r.status = PathStatus::Exact;
      break;
    case ob::PlannerStatus::APPROXIMATE_SOLUTION:
      r.status = PathStatus::Approximate;
      break;
    case ob::PlannerStatus::INVALID_START:
      r.status = PathStatus::InvalidStart;
      return r;
    case ob::PlannerStatus::INVALID_GOAL:
      r.status = PathStatus::InvalidGoal;
      return r;
    default:
      r.status = PathStatus::NoSolution;
      return r;
  }
  ob::PathPtr solution = pdef->getSolutionPath();
  if (!solution) {
    r.status = PathStatus::NoSolution;
    return r;
  }
  // RRT*'s own vertices, neither simplified nor interpolated: every edge is already <= range.
  const auto& path = *solution->as<og::PathGeometric>();
  r.waypoints.reserve(path.getStateCount());
  for (std::size_t i = 0; i < path.getStateCount(); ++i)
    r.waypoints.push_back(xyOf(path.getState(i)));
  r.goalDistance = r.status == PathStatus::Exact ? 0.0 : (r.waypoints.back() - goal).norm();
  r.cost = pathCost(model, r.waypoints, startHeading, weights, false);
  r.costWithTurns = pathCost(model, r.waypoints, startHeading, weights, true);
  return r;
}

}  // namespace rover::team
