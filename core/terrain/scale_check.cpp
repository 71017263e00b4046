#include "core/terrain/scale_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rover::terrain {

HeightRange plausibleHeights(Body b) {
  switch (b) {
    case Body::Earth:
      return {-11'400, 9'300};
    case Body::Moon:
      return {-9'600, 11'300};
    case Body::Mars:
      return {-8'700, 22'400};
    case Body::Unknown:
      break;
  }
  return {-11'400, 22'400};
}

double referenceRadius(Body b) {
  switch (b) {
    case Body::Earth:
      return 6'371'000;
    case Body::Moon:
      return 1'737'400;
    case Body::Mars:
      return 3'396'190;
    case Body::Unknown:
      break;
  }
  return 0;
}

namespace {

// For a sentence: "Mars", "the Moon", "Earth".
const char* displayName(Body b) {
  switch (b) {
    case Body::Earth:
      return "Earth";
    case Body::Moon:
      return "the Moon";
    case Body::Mars:
      return "Mars";
    case Body::Unknown:
      break;
  }
  return "any of Mars, the Moon and Earth";
}

// The body whose radius the heights sit round (within its relief), if any: the file holds radii.
Body radiiOf(double minHeight, double maxHeight, Body declared) {
  for (Body b : {declared, Body::Moon, Body::Mars, Body::Earth}) {
    const double r = referenceRadius(b);
    if (r == 0) continue;
    const HeightRange h = plausibleHeights(b);
    if (minHeight >= r + h.low && maxHeight <= r + h.high) return b;
  }
  return Body::Unknown;
}

}  // namespace

std::vector<ScaleWarning> scaleWarnings(double cellWidth, double cellHeight, double minHeight, double maxHeight,
                                        Body body) {
  std::vector<ScaleWarning> out;
  const double cell = std::max(cellWidth, cellHeight);
  if (std::isfinite(cell) && cell > kCoarsestRoverCell) {
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "cells of %.4g m are coarser than a micro-rover can use (at most %.0f m: slopes and rocks a rover "
                  "must avoid vanish inside one cell); distances and energies planned here are for a rover the "
                  "size of a cell",
                  cell, kCoarsestRoverCell);
    out.push_back({"coarse_cell", "cell", buf});
  }
  if (!std::isfinite(minHeight) || !std::isfinite(maxHeight)) return out;
  const HeightRange h = plausibleHeights(body);
  if (minHeight >= h.low && maxHeight <= h.high) return out;
  if (const Body r = radiiOf(minHeight, maxHeight, body); r != Body::Unknown) {
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "heights %.0f to %.0f m look like radii of %s (mean radius %.0f m), not heights: import again "
                  "with vertical_offset=%.0f",
                  minHeight, maxHeight, displayName(r), referenceRadius(r),
                  -referenceRadius(r));
    out.push_back({"heights_look_like_radii", "vertical_offset", buf});
    return out;
  }
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "heights %.0f to %.0f m lie outside the relief of %s (%.1f to %.1f km): the file may hold radii, "
                "raw counts (DN) or another datum; set vertical_scale and vertical_offset at import",
                minHeight, maxHeight, displayName(body), h.low / 1000, h.high / 1000);
  out.push_back({"heights_out_of_range", "vertical_scale", buf});
  return out;
}

}  // namespace rover::terrain
