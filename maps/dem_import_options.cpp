#include "maps/dem_import_options.hpp"

#include <cmath>
#include <cstdlib>

#include "core/common/error.hpp"

namespace rover::maps {

namespace {

constexpr const char* kNumber = "[-+0-9.eE]+";

[[noreturn]] void bad(const std::string& key, const std::string& message) {
  throw Error(ErrorCode::InvalidParameter, key, key + " " + message);
}

double number(const std::string& key, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v)) bad(key, "must be a finite number");
  return v;
}

std::array<double, 4> window(const std::string& key, const std::string& text, const std::string& what) {
  std::array<double, 4> w{};
  std::size_t at = 0;
  for (int k = 0; k < 4; ++k) {
    const std::size_t comma = text.find(',', at);
    if ((k < 3) != (comma != std::string::npos)) bad(key, "must be four numbers " + what);
    w[static_cast<std::size_t>(k)] = number(key, text.substr(at, comma == std::string::npos ? std::string::npos : comma - at));
    at = comma + 1;
  }
  if (!(w[2] > 0 && w[3] > 0)) bad(key, "needs a positive width and height");
  return w;
}

}  // namespace

const std::vector<DemOptionInfo>& demImportOptionInfos() {
  static const std::string n = kNumber;
  static const std::string four = "^" + n + "," + n + "," + n + "," + n + "$";
  static const std::vector<DemOptionInfo> infos{
      {"cell", "M", "Resample to square cells of M metres (GDAL warper: average when shrinking, bilinear "
                    "when enlarging); 0 or none keeps the file's own grid; otherwise [0.001, 100000].",
       "^(native|" + n + ")$"},
      {"crop", "X0,Y0,W,H", "Window in the file's CRS units: lower-left corner, width, height.", four},
      {"crop_px", "COL,ROW,W,H",
       "Window in pixels of the file: first column and row from the upper-left corner, width and "
       "height in pixels (as gdal_translate -srcwin); not with crop.",
       four},
      {"vertical_scale", "K", "Multiply heights by K (for files whose values are not metres), 0 < |K| <= 1e6.",
       "^" + n + "$"},
      {"vertical_offset", "M",
       "Add M metres to heights after vertical_scale (a file of planet radii: minus the body's radius, "
       "e.g. -1737400 on the Moon, -3396190 on Mars), |M| <= 1e8.",
       "^" + n + "$"},
      {"body", "auto|mars|moon|earth",
       "The planetary body (its gravity is the planners' default); auto reads it from the CRS.",
       "^(auto|mars|moon|earth)$"},
  };
  return infos;
}

std::optional<terrain::Body> bodyFromName(const std::string& name) {
  if (name == "mars") return terrain::Body::Mars;
  if (name == "moon") return terrain::Body::Moon;
  if (name == "earth") return terrain::Body::Earth;
  if (name == "auto") return std::nullopt;
  bad("body", "must be auto, mars, moon or earth");
}

DemImport parseDemImportOptions(const std::map<std::string, std::string>& values) {
  auto get = [&](const char* key) -> std::string {
    auto it = values.find(key);
    return it == values.end() ? std::string() : it->second;
  };
  DemImport out;
  if (const std::string cell = get("cell"); !cell.empty() && cell != "native") {
    const double c = number("cell", cell);
    if (c != 0 && !(c >= 1e-3 && c <= 1e5))
      bad("cell", "must be 0 (the file's own) or a number of metres in [0.001, 100000]");
    out.load.cellSize = c;
  }
  const std::string crop = get("crop"), cropPx = get("crop_px");
  if (!crop.empty() && !cropPx.empty()) bad("crop_px", "cannot be given with crop: choose one window");
  if (!crop.empty()) out.load.crop = window("crop", crop, "X0,Y0,W,H in the file's CRS units");
  if (!cropPx.empty()) {
    const auto w = window("crop_px", cropPx, "COL,ROW,W,H in pixels");
    for (double v : w)
      if (v < 0 || std::trunc(v) != v || v > 1e9) bad("crop_px", "must be whole numbers of pixels in [0, 1e9]");
    out.load.cropPixels = w;
  }
  if (const std::string k = get("vertical_scale"); !k.empty()) {
    const double v = number("vertical_scale", k);
    if (v == 0 || std::fabs(v) > 1e6) bad("vertical_scale", "must be non-zero with |K| <= 1e6");
    out.load.verticalScale = v;
  }
  if (const std::string m = get("vertical_offset"); !m.empty()) {
    const double v = number("vertical_offset", m);
    if (std::fabs(v) > 1e8) bad("vertical_offset", "must be within ±1e8 metres");
    out.load.verticalOffset = v;
  }
  if (const std::string b = get("body"); !b.empty()) out.body = bodyFromName(b);
  return out;
}

}  // namespace rover::maps
