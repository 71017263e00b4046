#pragma once
// Paper 000 eq. 5: E = E_forward + E_rotate for a rover that drives straight between cells and
// spot-turns at each step (after Oikawa et al.).
#include "core/coverage/coverage_params.hpp"

namespace rover::coverage {

// Driving `horizontal` metres while climbing `dh` metres:
// m·g·(μ·cosθ + sinθ)·s / η with θ = atan2(dh, horizontal) and s the distance along the slope.
// Clamped at 0 downhill: the drive does not recover energy (no regenerative braking).
double forwardEnergy(const EnergyModel& e, double horizontal, double dh);
// Spot turn between two of the 8 directions: turnJoulesPerRad · |Δψ|.
double turnEnergy(const EnergyModel& e, int fromDir, int toDir);

}  // namespace rover::coverage
