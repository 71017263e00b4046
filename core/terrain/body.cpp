#include "core/terrain/body.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace rover::terrain {

const char* bodyName(Body b) {
  switch (b) {
    case Body::Earth:
      return "earth";
    case Body::Moon:
      return "moon";
    case Body::Mars:
      return "mars";
    case Body::Unknown:
      break;
  }
  return "unknown";
}

double bodyGravity(Body b) {
  switch (b) {
    case Body::Earth:
      return 9.81;
    case Body::Moon:
      return 1.62;
    case Body::Mars:
      return 3.71;
    case Body::Unknown:
      break;
  }
  return 0.0;
}

namespace {

Body fromAxis(double a) {
  if (!std::isfinite(a) || a <= 0) return Body::Unknown;
  // Mars: IAU 2000 3 396 190 m, MOLA-era spheres 3 393 400 and 3 397 000 m.
  if (a > 3'390'000 && a < 3'400'000) return Body::Mars;
  if (std::fabs(a - 1'737'400) < 2'000) return Body::Moon;
  // Earth: every reference ellipsoid in use lies within a kilometre of 6 378 km.
  if (a > 6'377'000 && a < 6'379'000) return Body::Earth;
  return Body::Unknown;
}

Body fromName(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  auto has = [&](const char* w) { return s.find(w) != std::string::npos; };
  if (has("mars")) return Body::Mars;
  if (has("moon") || has("lunar") || has("luna")) return Body::Moon;
  if (has("earth") || has("wgs") || has("grs") || has("nad") || has("etrs") || has("clarke") ||
      has("bessel") || has("krassowsk") || has("hayford") || has("airy"))
    return Body::Earth;
  return Body::Unknown;
}

}  // namespace

Body detectBody(const std::string& ellipsoidName, const std::string& datumName,
                double semiMajorAxis) {
  if (Body b = fromAxis(semiMajorAxis); b != Body::Unknown) return b;
  if (Body b = fromName(ellipsoidName); b != Body::Unknown) return b;
  return fromName(datumName);
}

}  // namespace rover::terrain
