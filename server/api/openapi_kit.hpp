#pragma once
// The small JSON-schema builders the OpenAPI document's files share (openapi.cpp,
// openapi_schemas.cpp, openapi_studies.cpp): one definition of "a string with a description",
// "an object with these required properties", "a name as every named object takes it".
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/common/enum_names.hpp"
#include "server/json/json_edge.hpp"

namespace rover::api::openapi::kit {

using nlohmann::json;

inline json nullable(json schema) {
  schema["nullable"] = true;
  return schema;
}
inline json str(const std::string& description = "") {
  json s{{"type", "string"}};
  if (!description.empty()) s["description"] = description;
  return s;
}
inline json num(const std::string& description = "") {
  json s{{"type", "number"}};
  if (!description.empty()) s["description"] = description;
  return s;
}
inline json integer(double min, double max) { return {{"type", "integer"}, {"minimum", min}, {"maximum", max}}; }
inline json object(json properties, std::vector<std::string> required = {}, bool closed = false) {
  json s{{"type", "object"}, {"properties", std::move(properties)}};
  if (!required.empty()) s["required"] = required;
  if (closed) s["additionalProperties"] = false;
  return s;
}
// A string field whose values are an enum's names, from the enum's one table (enum_names.hpp).
template <NamedEnum E>
inline json oneOf() {
  return {{"type", "string"}, {"enum", enumNames<E>()}};
}

inline json name(const std::string& description) {
  json s = str(description + " UTF-8, at most " + std::to_string(rover::json::kMaxNameChars) +
               " characters, no control, zero-width or text-direction characters.");
  s["maxLength"] = rover::json::kMaxNameChars;
  return s;
}

// `s` (a string schema) with minLength 1: a name that may not be empty.
inline json withMinLength(json s) {
  s["minLength"] = 1;
  return s;
}

}  // namespace rover::api::openapi::kit
