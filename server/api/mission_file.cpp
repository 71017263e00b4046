#include "server/api/mission_file.hpp"

namespace rover::api {

using nlohmann::json;

json missionFile(const store::MissionRecord& m, const std::string& demSha256,
                 const std::string& version) {
  const json& spec = m.spec.is_object() ? m.spec : json::object();
  json f{{"format", kMissionFileFormat},
         {"version", kMissionFileVersion},
         {"roverplan", version},
         {"map", m.mapId},
         {"map_name", m.mapName.empty() ? json(nullptr) : json(m.mapName)},
         {"dem_sha256", demSha256.empty() ? json(nullptr) : json(demSha256)},
         {"pdm", m.pdmId.empty() ? json(nullptr) : json(m.pdmId)},
         {"planner", m.planner},
         {"rovers", spec.value("rovers", json::array())},
         {"params", spec.value("params", json::object())}};
  if (spec.contains("pace")) f["pace"] = spec["pace"];
  // The zones the run kept out of, as the request gave them (local frame): a re-run keeps out too.
  if (spec.contains("keep_out") && !spec["keep_out"].is_null()) f["keep_out"] = spec["keep_out"];
  // The area it planned in (issue 24): a re-run plans there too (on a big map it must).
  if (spec.contains("area") && !spec["area"].is_null()) f["area"] = spec["area"];
  // The versions it used (issue 26): duplicate-and-edit reopens those.
  if (spec.contains("used") && spec["used"].is_object()) f["used"] = spec["used"];
  // The run's current label (its request's name until renamed; a cleared label clears it).
  if (!m.label.empty()) f["name"] = m.label;
  return f;
}

}  // namespace rover::api
