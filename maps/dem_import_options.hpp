#pragma once
// How a DEM is read when it becomes a map: cell size, a crop window (in the file's CRS units or in
// pixels), a vertical scale and the planetary body. One table and one parser for the CLI
// (--crop, --crop-px, --vertical-scale, --body), the upload route (?crop=&crop_px=&vertical_scale=
// &body= or multipart fields of those names) and the OpenAPI document, so they accept the same
// values with the same messages.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/terrain/body.hpp"
#include "maps/dem_io.hpp"

namespace rover::maps {

struct DemOptionInfo {
  std::string key;      // snake_case: the query/form field; the CLI option is the kebab-case form
  std::string metavar;  // "X0,Y0,W,H"
  std::string doc;      // one sentence
  std::string pattern;  // the value's shape as an OpenAPI/ECMA regular expression
};
// cell, crop, crop_px, vertical_scale, body.
const std::vector<DemOptionInfo>& demImportOptionInfos();

struct DemImport {
  LoadOptions load;                   // cellSize, crop, cropPixels, verticalScale
  std::optional<terrain::Body> body;  // declared; none = from the file's CRS
};

// The values as typed, by key; a missing or empty value keeps its default. Unknown keys are the
// caller's business. Throws rover::Error (InvalidParameter) naming the key: a cell outside 0 or
// [0.001, 100000] m, a crop that is not four finite numbers with positive width and height, both
// crop and crop_px, a vertical scale that is zero or not finite or over 1e6 in size, a body not in
// auto|mars|moon|earth.
DemImport parseDemImportOptions(const std::map<std::string, std::string>& values);

// "mars" | "moon" | "earth" (or "auto": none).
std::optional<terrain::Body> bodyFromName(const std::string& name);

}  // namespace rover::maps
