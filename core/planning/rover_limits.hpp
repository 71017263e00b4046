#pragma once
// How many rovers one mission may hold, for every planner and every edge (API, CLI, studies):
// the team planners' traffic table and the coverage occupancy are sized for it, and the request
// limits in README say it.
#include <cstddef>
#include <string>

#include "core/common/error.hpp"

namespace rover::planning {

inline constexpr int kMaxRovers = 64;

// Throws InvalidInput "rovers" unless 1 <= count <= kMaxRovers.
inline void checkRoverCount(std::size_t count) {
  if (count < 1 || count > static_cast<std::size_t>(kMaxRovers))
    throw Error(ErrorCode::InvalidInput, "rovers",
                "between 1 and " + std::to_string(kMaxRovers) + " rovers are supported");
}

}  // namespace rover::planning
