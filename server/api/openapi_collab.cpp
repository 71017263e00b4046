// The OpenAPI schemas of several operators on one server (issue 26): versions and their
// conflicts, single zones, the event stream's messages, the history of PDMs and zone sets.
#include "server/api/openapi.hpp"
#include "server/api/openapi_kit.hpp"
#include "server/store/database.hpp"
#include "server/streams/event_hub.hpp"

namespace rover::api::openapi {

using namespace kit;

json collabSchemas(const json& zoneFeature) {
  json s = json::object();
  const json version = {{"type", "integer"}, {"minimum", 0},
                        {"description", "The object's version: 1 when created, +1 per saved change (also its ETag "
                                        "\"v<N>\"); send it back (If-Match) to change it."}};
  s["VersionConflict"] = object(
      {{"error", object({{"code", {{"type", "string"}, {"enum", {"version_conflict"}}}},
                         {"message", str("Which version was named, which is stored.")},
                         {"field", str("If-Match")},
                         {"current", {{"type", "object"}, {"description", "The object as stored now (with its version)."}}}},
                        {"code", "message", "field", "current"})}},
      {"error"});
  json zone = zoneFeature;
  zone["properties"]["id"] = str("The zone's id on its map (\"z1\", ...), never reused.");
  zone["properties"]["version"] = version;
  zone["properties"]["zones_version"] = {{"type", "integer"}, {"description", "The map's zone set's version."}};
  zone["description"] = "One keep-out zone: a GeoJSON Feature with a Polygon (properties.version is its version too).";
  s["Zone"] = zone;
  s["ZoneDeleted"] = object({{"deleted", str("The zone's id.")}, {"zones_version", {{"type", "integer"}}}},
                            {"deleted", "zones_version"});
  s["HistoryEntry"] = object({{"version", {{"type", "integer"}}},
                              {"by", str("Who saved it (\"\" when unknown).")},
                              {"at", str("When, ISO 8601 UTC.")},
                              {"body", {{"type", "object"}, {"description", "The saved object (one version's GET only)."}}}},
                             {"version", "by", "at"});
  s["History"] = {{"type", "array"},
                  {"items", ref("HistoryEntry")},
                  {"maxItems", store::kHistoryPerObject},
                  {"description", "Saved versions, newest first: the last " + std::to_string(store::kHistoryPerObject) +
                                      " of the object are kept."}};
  s["PdmChange"] = object({{"name", name("The PDM's new name.")},
                           {"components", {{"type", "array"}, {"minItems", 1}, {"items", {{"type", "object"}}}}},
                           {"version", version}});
  return s;
}

// What WS /api/events sends (listed under x-websockets: OpenAPI 3.0 components only count as used
// from paths).
json eventMessageSchema() {
  const json event = object(
      {{"seq", {{"type", "integer"}, {"description", "Global, gap-free (a map-filtered stream skips other maps' numbers)."}}},
       {"kind", {{"type", "string"}, {"enum", {"created", "changed", "deleted", "presence", "left"}}}},
       {"object", {{"type", "string"}, {"enum", {"map", "pdm", "zone", "zones", "mission", "study", "presence"}}}},
       {"id", str("The object's id (a zone's id on its map; the map's id for a zone set; a connection's for presence).")},
       {"map", str("The map it belongs to, \"\" when none.")},
       {"version", {{"type", "integer"}, {"description", "Its version after the change, 0 when deleted or unversioned."}}},
       {"by", str("The operator (named token, X-Operator or hello name), \"\" when unknown.")},
       {"at", str("ISO 8601 UTC.")},
       {"extra", object({{"name", str()}, {"editing", str()}})}},
      {"seq", "kind", "object", "id", "map", "version", "by", "at"});
  return {
      {"description",
       "A message of WS /api/events: {type:\"events\", events:[Event...]} (in seq order), {type:\"ready\", seq, "
       "connection, ring, presence:[{id,name,map,editing}]} once the replay is sent, or {type:\"resync_required\", "
       "since, oldest, message} (then the server closes) when the events asked for are older than the last " +
           std::to_string(streams::EventHub::kRingEvents) + " kept."},
      {"type", "object"},
      {"properties",
       {{"type", {{"type", "string"}, {"enum", {"events", "ready", "resync_required"}}}},
        {"events", {{"type", "array"}, {"items", event}}},
        {"seq", {{"type", "integer"}}},
        {"presence", {{"type", "array"}, {"items", {{"type", "object"}}}}}}},
      {"required", {"type"}}};
}

}  // namespace rover::api::openapi
