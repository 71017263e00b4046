#pragma once
// A coverage world from a DEM (paper 000 §III.B, SPEC §1/§2): cells the traversability layer calls
// impassable, and cells without data, are obstacles; heights feed the β·|Δh| cost, energy and pitch.
#include "core/coverage/world.hpp"
#include "core/terrain/layers.hpp"

namespace rover::coverage {

World worldFromDem(const terrain::Dem& dem, const terrain::TraversabilityParams& params = {});

}  // namespace rover::coverage
