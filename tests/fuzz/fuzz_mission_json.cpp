// libFuzzer harness for the JSON edge (issue 14): bytes -> parseJsonLimited (size/depth limits)
// -> parseMissionRequest for every registered planner, and -> gaussiansFromJson -> the PDM bounds
// and a small discretisation. Expected rejections (http::ApiError, rover::Error) are fine; a crash,
// a sanitizer report or any other exception is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/common/error.hpp"
#include "core/pdm/pdm.hpp"
#include "core/planning/planner.hpp"
#include "server/http/http_types.hpp"
#include "server/json/json_edge.hpp"
#include "server/json/mission_request.hpp"
#include "server/json/pdm_json.hpp"

using namespace rover;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const PlannerRegistry registry = makeBuiltinRegistry();
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  nlohmann::json body;
  try {
    body = json::parseJsonLimited(text, json::kMissionJsonLimits);
  } catch (const http::ApiError&) {
    return 0;
  }
  // The planner named in the input first, then each registered one in its place.
  try {
    (void)json::parseMissionRequest(body, registry);
  } catch (const http::ApiError&) {
  }
  for (const auto& name : registry.names()) {
    body["planner"] = name;
    try {
      auto request = json::parseMissionRequest(body, registry);
      (void)request.spec.dump();
    } catch (const http::ApiError&) {
    }
  }
  // The same body as a PDM request on a 40 × 30 m map of 1 m cells.
  try {
    auto components = json::gaussiansFromJson(body);
    const GridGeometry g{30, 40, 1.0, 1.0};
    pdm::validateGaussians(components, g);
    if (components.size() <= 8) (void)pdm::discretise(components, g);
  } catch (const Error&) {
  }
  return 0;
}
