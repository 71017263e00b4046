#pragma once
// The legend strip under a layer rendering (render.cpp): a colour ramp with its title and
// labelled ticks, or class swatches with their names, in the 5×7 bitmap font.
#include <string>
#include <utility>
#include <vector>

#include "maps/painter.hpp"

namespace rover::maps {

// A colour ramp from lo to hi; `colour` maps a value (source units) to its colour.
struct RampLegend {
  std::string title;
  double lo = 0, hi = 1;
  std::vector<double> ticks;  // interior values labelled besides lo and hi
  Rgba (*colour)(double, const RampLegend&) = nullptr;
};

// One class swatch.
struct ClassItem {
  Rgba colour;
  std::string label;
};

// The strip's narrowest width and a ramp legend's height, in pixels.
constexpr int kMinLegendWidth = 160;
constexpr int kRampLegendHeight = 32;

// Draws the ramp legend across `img` from row y0 (kRampLegendHeight rows).
void drawRampLegend(Image& img, int y0, const RampLegend& lg);
// Swatches flow left to right and wrap; returns the strip height (at least 28 px) and, when
// `positions` is given, each swatch's place in it.
int layoutClassLegend(int width, const std::vector<ClassItem>& items, std::vector<std::pair<int, int>>* positions);
// Draws the class legend across `img` from row y0, `height` rows (layoutClassLegend's).
void drawClassLegend(Image& img, int y0, int height, const std::string& title, const std::vector<ClassItem>& items);

}  // namespace rover::maps
