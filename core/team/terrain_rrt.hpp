#pragma once
// Individual rover paths: RRT* (Karaman & Frazzoli 2011, OMPL's RRTstar) on terrain with the cost
// of paper 001 §3.6 eq. 9 (after Takemura & Ishigami 2017), SPEC §3.2:
//   cost(q_i) = W_R·R_i/N_R + W_φ·φ_i/N_φ + W_θ·θ_i/N_θ + W_ψ·Δψ_i/N_ψ
// One planning problem per rover per route segment; the tree grows to a fixed number of vertices so
// that the result depends on the seed alone, never on the clock.
//
// Everything OMPL stays in terrain_rrt.cpp: the eq. 9 objective and the validity checks there are
// thin wrappers around TerrainEdgeModel below, which tests and the team planner can use directly.
// Positions are in the local frame (x east, y north, metres from the raster's south-west corner),
// headings in radians counter-clockwise from east (SPEC §0).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include "core/common/cancel.hpp"
#include "core/common/enum_names.hpp"
#include "core/grid/raster.hpp"
#include "core/terrain/dem.hpp"

namespace rover::team {

// Weights W and normalisers N of eq. 9. Defaults are paper 001's: W = (0.1, 0.4, 0.4, 0.1),
// N = (1 m, 15°, 15°, 60°). Angles in radians here; user-facing layers show degrees.
struct TerrainCostWeights {
  double wR = 0.1;                                  //                        key: w_r
  double wPhi = 0.4;                                // roll                   key: w_phi
  double wTheta = 0.4;                              // pitch                  key: w_theta
  double wPsi = 0.1;                                // heading change         key: w_psi
  double nR = 1.0;                                  // m (the RRT* range)     key: n_r
  double nPhi = 15.0 * std::numbers::pi / 180.0;    // rad (15°)              key: n_phi
  double nTheta = 15.0 * std::numbers::pi / 180.0;  // rad (15°)              key: n_theta
  double nPsi = 60.0 * std::numbers::pi / 180.0;    // rad (60°)              key: n_psi

  // Throws rover::Error(InvalidParameter) with the key as field: weights must be finite and >= 0,
  // normalisers finite and > 0.
  void validate() const;
};

// How eq. 9's φ and θ of an edge are evaluated (issue 25).
enum class EdgeEvaluation {
  // The paper mode's and planPath's own default: `sampled`, except `patch` in the team's timed
  // mode (coordinate() resolves it).
  Auto,
  // Paper 001: the largest |roll| and |pitch| over samples edge_resolution apart.
  Sampled,
  // Ours: the exact largest |roll| and |pitch| over the whole edge on the bilinear surface. Inside
  // one bilinear patch (the square between four cell centres) ∂z/∂x is linear in y alone and
  // ∂z/∂y in x alone, so along a straight edge both — and with them tan pitch = ∇z·(cosψ, sinψ)
  // and tan roll = ∇z·(−sinψ, cosψ) — are affine in the distance driven: their largest magnitude
  // on a piece of the edge is at one of its two ends. The edge is cut where it crosses a row or
  // column of cell centres and each piece is evaluated at its ends with its own patch: 2 × (pieces)
  // cheap evaluations instead of 4 bilinear samples per cell, and never below the sampled value.
  Patch,
};

struct RrtParams {
  double range = 1.0;      // m, the longest edge of the tree (paper 001: 1 m)      key: range
  int maxVertices = 1250;  // the tree is grown to this many vertices (paper 001) key: max_vertices
  double clearance = 2.0;  // m around the box of start and goal, clipped to the map key: clearance
  // rad (15°); |roll| or |pitch| >= it anywhere on an edge makes it invalid   key: attitude_limit
  double attitudeLimit = 15.0 * std::numbers::pi / 180.0;
  std::uint64_t seed = 1;  //                                                       key: seed
  // m between the attitude/validity samples of an edge; 0 = a quarter of the DEM cell
  double edgeResolution = 0.0;  //                                             key: edge_resolution
  double goalBias = 0.05;       // probability of sampling the goal (OMPL's default)  key: goal_bias
  // Safety cap on RRT* iterations (deterministic, like the vertex count): a start boxed in by
  // impassable cells could never grow the tree to maxVertices.           key: max_iterations
  int maxIterations = 100000;
  EdgeEvaluation evaluation = EdgeEvaluation::Auto;  //                          key: edge_evaluation

  // Throws rover::Error(InvalidParameter) with the key as field.
  void validate() const;
};

// The search region: bounding box of start and goal grown by the clearance, clipped to the map.
struct SearchBounds {
  Eigen::Vector2d min{0, 0};
  Eigen::Vector2d max{0, 0};
  bool contains(const Eigen::Vector2d& p) const {
    return p.x() >= min.x() && p.y() >= min.y() && p.x() <= max.x() && p.y() <= max.y();
  }
};
SearchBounds searchBounds(const GridGeometry& map, const Eigen::Vector2d& start,
                          const Eigen::Vector2d& goal, double clearance);
// The whole map as search bounds.
SearchBounds mapBounds(const GridGeometry& map);
// The spacing of the validity samples along an edge: `params.edgeResolution`, or a quarter of
// the map's (smaller) cell side when it is 0.
double edgeResolutionOn(const GridGeometry& map, const RrtParams& params);

// |to − from| wrapped to [0, π]: the smaller turn from heading `from` to heading `to`.
double headingChange(double from, double to);

// A disc the path must stay out of (ours, for prioritised planning, SPEC §3.4; not an operator's
// keep-out zone, which reaches the planner as the class KeepOut, core/planning/keep_out.hpp): where a
// higher-priority rover was when a candidate path came too close to it. Re-planning with only a
// new seed cannot separate a head-on pair on open ground — RRT* converges to the same straight
// line whatever the seed — so each retry also keeps out of the places the earlier tries collided.
struct KeepOutZone {
  Eigen::Vector2d centre{0, 0};  // local frame, m
  double radius = 0;             // m
};

// The ground RRT* may use around a guide path (ours, traversal_lattice.hpp): the map cells whose
// centre is near the guide, and the box around them that bounds the sampling.
struct Corridor {
  SearchBounds bounds;           // local frame, clipped to the map
  GridGeometry map;              // the DEM's grid
  int row0 = 0, col0 = 0;        // map cell of the mask's (0, 0)
  Raster<std::uint8_t> mask;     // 1 = inside; rows × cols of the window
  bool contains(const Eigen::Vector2d& p) const {
    auto c = localToCell(map, p);
    return c && containsCell(*c);
  }
  // `c`: a cell of `map`.
  bool containsCell(const CellIndex& c) const {
    const int r = c.row - row0, k = c.col - col0;
    return mask.geometry.contains(r, k) && mask(r, k) != 0;
  }
};

// The four quantities of eq. 9 for one edge.
struct EdgeTerms {
  double length = 0;         // R, m
  double roll = 0;           // φ, the largest |roll| sampled along the edge, rad
  double pitch = 0;          // θ, the largest |pitch| sampled along the edge, rad
  double headingChange = 0;  // Δψ, rad in [0, π]
  double cost(const TerrainCostWeights& w) const {
    return w.wR * length / w.nR + w.wPhi * roll / w.nPhi + w.wTheta * pitch / w.nTheta +
           w.wPsi * headingChange / w.nPsi;
  }
};

// Validity and eq. 9 terms of straight edges on one DEM and its traversability classes
// (terrain::TerrainClass values). Holds references: the rasters must outlive it. Const and
// thread-safe.
class TerrainEdgeModel {
 public:
  // `classes` must have the DEM's grid (rows, cols); throws InvalidInput otherwise.
  // `edgeResolution` > 0 is the spacing of the samples along an edge.
  TerrainEdgeModel(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                   SearchBounds bounds, double attitudeLimit, double edgeResolution);
  // Temporaries would dangle.
  TerrainEdgeModel(terrain::Dem&&, const Raster<std::uint8_t>&, SearchBounds, double,
                   double) = delete;
  TerrainEdgeModel(const terrain::Dem&, Raster<std::uint8_t>&&, SearchBounds, double,
                   double) = delete;

  // A disc around a start that is not pointValid (the simulated rover cut a corner onto an
  // impassable cell or too steep a spot): inside it the class and attitude checks are waived so
  // the rover can drive off; data, bounds and keep-out zones still apply. Radius 0 = none.
  void setEscape(const Eigen::Vector2d& centre, double radius) {
    escapeCentre_ = centre;
    escapeRadius_ = radius;
  }

  // Zones every point must stay out of (strictly outside the radius). Empty by default.
  void setKeepOut(std::vector<KeepOutZone> zones) { keepOut_ = std::move(zones); }
  // Points must also lie in the corridor (null: no corridor). Not owned.
  void setCorridor(const Corridor* corridor) { corridor_ = corridor; }
  // edgeTerms' φ and θ: Patch, the exact maxima over the edge; otherwise (the default) the
  // samples'. Validity (edgeValid, validEdgeTerms) always reads the samples.
  void setEvaluation(EdgeEvaluation e) { patch_ = e == EdgeEvaluation::Patch; }

  // Inside the bounds and the map, outside every keep-out zone, on a cell with data that is not
  // Impassable, with a defined surface (bilinear interpolation needs the four surrounding cell
  // centres to have data).
  bool pointValid(const Eigen::Vector2d& p) const;
  // pointValid, and the terrain's full slope (the gradient's magnitude) below the attitude limit:
  // the rover stops and turns in place at a path vertex, sweeping through every heading, so a
  // vertex must be safe whichever way it faces (ours: checking only the two edges' headings let
  // the simulated rover exceed 15° while turning on a slope).
  bool turnValid(const Eigen::Vector2d& p) const;
  // Every sample of the edge (both ends included, at most edgeResolution apart) is pointValid and
  // has |roll| and |pitch| strictly below the attitude limit for the edge's heading.
  bool edgeValid(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  // R, φ, θ of the edge a→b (φ, θ over the same samples as edgeValid, samples without a surface
  // skipped; with EdgeEvaluation::Patch their exact maxima over the edge, patches without a
  // surface skipped); Δψ is the turn from `previousHeading` to the edge's heading (0 for a zero-length
  // edge).
  EdgeTerms edgeTerms(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                      double previousHeading) const;
  // Same without a turn (Δψ = 0).
  EdgeTerms edgeTerms(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  // edgeValid and edgeTerms in one pass over the samples: the terms when the edge is valid.
  std::optional<EdgeTerms> validEdgeTerms(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;

  // On a map cell an operator's keep-out zone overlaps (the class KeepOut,
  // core/planning/keep_out.hpp). No point on such a cell is ever valid.
  bool inZone(const Eigen::Vector2d& p) const;

  const SearchBounds& bounds() const { return bounds_; }
  double edgeResolution() const { return resolution_; }

 private:
  const terrain::Dem& dem_;
  const Raster<std::uint8_t>& classes_;
  SearchBounds bounds_;
  double limit_;
  double resolution_;
  std::vector<KeepOutZone> keepOut_;
  const Corridor* corridor_ = nullptr;
  bool patch_ = false;
  Eigen::Vector2d escapeCentre_{0, 0};
  double escapeRadius_ = 0;
  bool outsideKeepOut(const Eigen::Vector2d& p) const;
  // The largest |tan pitch| and |tan roll| over the edge, exactly (EdgeEvaluation::Patch); false
  // where that form does not apply (an end off the map): then the samples.
  bool patchTangents(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double c, double s,
                     double& tanPitch, double& tanRoll) const;
  bool outsideDiscs(const Eigen::Vector2d& p) const;
  bool allowed(const Eigen::Vector2d& p) const;
  bool inEscape(const Eigen::Vector2d& p) const {
    return escapeRadius_ > 0 && (p - escapeCentre_).squaredNorm() <= escapeRadius_ * escapeRadius_;
  }
};

// eq. 9 summed over a polyline (first point = start). With `turnsAtEveryVertex` false this is what
// the planner minimises (Δψ only on the first edge, from `startHeading`, see terrain_rrt.cpp); with
// true, Δψ is charged at every vertex as the turn from the previous edge — the turns the rover
// really makes.
double pathCost(const TerrainEdgeModel& model, const std::vector<Eigen::Vector2d>& path,
                double startHeading, const TerrainCostWeights& weights, bool turnsAtEveryVertex);

enum class PathStatus {
  Exact,         // the path ends at the goal
  Approximate,   // no valid path found; the path ends at the tree vertex closest to the goal
  NoSolution,    // the tree never left the start
  InvalidStart,  // start outside the map or not pointValid
  InvalidGoal,   // goal outside the map or not pointValid
  Cancelled,     // the cancel token was set; no path returned
};

struct PathResult {
  PathStatus status = PathStatus::NoSolution;
  std::vector<Eigen::Vector2d> waypoints;  // local frame, start first; RRT*'s own vertices
  double cost = 0;           // eq. 9 as minimised by RRT* (pathCost(..., false)); 0 without path
  double costWithTurns = 0;  // eq. 9 with Δψ at every vertex (pathCost(..., true))
  double goalDistance = 0;   // m from the last waypoint to the goal (0 when Exact)
  int vertices = 0;          // vertices of the RRT* tree (OMPL PlannerData) when it stopped
  int iterations = 0;        // RRT* iterations (samples drawn)
  // The planner proved that no path reaches the goal outside the keep-out zones (the guided
  // planner: none on its lattice); an Approximate path then only ends short of it.
  bool goalCutOff = false;
  bool hasPath() const { return status == PathStatus::Exact || status == PathStatus::Approximate; }
};

// Plans one rover's path from `start` (heading `startHeading`) to `goal` with RRT* (paper 001
// §3.6): bounds from searchBounds(), range `params.range`, eq. 9 cost, the tree grown until it has
// `params.maxVertices` vertices (or `params.maxIterations` iterations, or cancellation).
// start == goal gives Exact with that one waypoint and no search.
// Deterministic for a given seed; safe to call concurrently from several threads (each call builds
// its own OMPL objects and seeded random generators). Bad parameters throw rover::Error.
// A start on impassable or too steep ground (but on the map, with data) is escaped: the checks are
// waived within 0.5 m of it (TerrainEdgeModel::setEscape). `keepOut`: discs the path stays out of (a start or goal inside one is InvalidStart/InvalidGoal).
// `corridor` (ours): sample and stay inside it, within its bounds, instead of the start/goal box.
PathResult planPath(const terrain::Dem& dem, const Raster<std::uint8_t>& classes,
                    const Eigen::Vector2d& start, double startHeading, const Eigen::Vector2d& goal,
                    const RrtParams& params = {}, const TerrainCostWeights& weights = {},
                    const CancelToken* cancel = nullptr,
                    const std::vector<KeepOutZone>& keepOut = {},
                    const Corridor* corridor = nullptr);

}  // namespace rover::team

// The names of the values above (enum_names.hpp).
namespace rover {
template <>
struct EnumNames<team::EdgeEvaluation> {
  static constexpr std::array<EnumName<team::EdgeEvaluation>, 3> table{{
      {team::EdgeEvaluation::Auto, "auto"},
      {team::EdgeEvaluation::Sampled, "sampled"},
      {team::EdgeEvaluation::Patch, "patch"},
  }};
};
template <>
struct EnumNames<team::PathStatus> {
  static constexpr std::array<EnumName<team::PathStatus>, 6> table{{
      {team::PathStatus::Exact, "exact"},
      {team::PathStatus::Approximate, "approximate"},
      {team::PathStatus::NoSolution, "no_solution"},
      {team::PathStatus::InvalidStart, "invalid_start"},
      {team::PathStatus::InvalidGoal, "invalid_goal"},
      {team::PathStatus::Cancelled, "cancelled"},
  }};
};
}  // namespace rover
