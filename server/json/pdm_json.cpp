#include "server/json/pdm_json.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/common/error.hpp"

namespace rover::json {

namespace {
double number(const nlohmann::json& obj, const char* key, std::size_t i, bool required,
              double fallback) {
  const std::string field = "components[" + std::to_string(i) + "]." + key;
  auto it = obj.find(key);
  if (it == obj.end()) {
    if (required) throwInvalidParameter(field, "is required");
    return fallback;
  }
  if (!it->is_number()) throwInvalidParameter(field, "must be a number");
  const double v = it->get<double>();
  if (!std::isfinite(v)) throwInvalidParameter(field, "must be a finite number");
  return v;
}
}  // namespace

std::vector<pdm::Gaussian> gaussiansFromJson(const nlohmann::json& j) {
  const nlohmann::json* list = &j;
  if (j.is_object()) {
    auto it = j.find("components");
    if (it == j.end()) throwInvalidParameter("components", "is required");
    list = &*it;
  }
  if (!list->is_array()) throwInvalidParameter("components", "must be an array of Gaussians");
  // Bounded before anything is built: the discretisation costs one window per component.
  if (list->size() > pdm::kMaxComponents)
    throwInvalidParameter("components", "at most " + std::to_string(pdm::kMaxComponents) + " components, got " +
                                            std::to_string(list->size()));
  std::vector<pdm::Gaussian> out;
  for (std::size_t i = 0; i < list->size(); ++i) {
    const auto& c = (*list)[i];
    if (!c.is_object())
      throwInvalidParameter("components[" + std::to_string(i) + "]", "must be an object");
    for (const auto& [key, value] : c.items()) {
      static const char* known[] = {"x", "y", "sigma_x", "sigma_y", "rotation_deg", "weight"};
      if (std::find(std::begin(known), std::end(known), key) == std::end(known))
        throw Error(ErrorCode::UnknownParameter, "components[" + std::to_string(i) + "]." + key.substr(0, 64),
                    "unknown field '" + key.substr(0, 64) + "'");
    }
    pdm::Gaussian g;
    g.mean = {number(c, "x", i, true, 0), number(c, "y", i, true, 0)};
    g.sigmaX = number(c, "sigma_x", i, true, 0);
    g.sigmaY = number(c, "sigma_y", i, false, g.sigmaX);
    const double rotationDeg = number(c, "rotation_deg", i, false, 0);
    if (std::fabs(rotationDeg) > 360)
      throwInvalidParameter("components[" + std::to_string(i) + "].rotation_deg", "must be in [-360, 360] degrees");
    g.rotation = rotationDeg * std::numbers::pi / 180.0;
    g.weight = number(c, "weight", i, false, 1.0);
    out.push_back(g);
  }
  pdm::validateGaussians(out);
  return out;
}

nlohmann::json toJson(const std::vector<pdm::Gaussian>& components) {
  nlohmann::json arr = nlohmann::json::array();
  for (const auto& g : components)
    arr.push_back({{"x", g.mean.x()},
                   {"y", g.mean.y()},
                   {"sigma_x", g.sigmaX},
                   {"sigma_y", g.sigmaY},
                   {"rotation_deg", g.rotation * 180.0 / std::numbers::pi},
                   {"weight", g.weight}});
  return {{"components", arr}};
}

nlohmann::json toStoredJson(const std::vector<pdm::Gaussian>& components) {
  nlohmann::json arr = nlohmann::json::array();
  for (const auto& g : components)
    arr.push_back({{"x", g.mean.x()},
                   {"y", g.mean.y()},
                   {"sigma_x", g.sigmaX},
                   {"sigma_y", g.sigmaY},
                   {"rotation_rad", g.rotation},
                   {"weight", g.weight}});
  return {{"format", "gaussians/1"}, {"components", arr}};
}

std::vector<pdm::Gaussian> gaussiansFromStoredJson(const nlohmann::json& j) {
  if (!j.is_object() || j.value("format", "") != "gaussians/1" || !j.contains("components") ||
      !j["components"].is_array())
    throw Error(ErrorCode::InvalidInput, "components", "not a stored Gaussian PDM (gaussians/1)");
  std::vector<pdm::Gaussian> out;
  try {
    for (const auto& c : j["components"]) {
      pdm::Gaussian g;
      g.mean = {c.at("x").get<double>(), c.at("y").get<double>()};
      g.sigmaX = c.at("sigma_x").get<double>();
      g.sigmaY = c.at("sigma_y").get<double>();
      g.rotation = c.at("rotation_rad").get<double>();
      g.weight = c.at("weight").get<double>();
      out.push_back(g);
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(ErrorCode::InvalidInput, "components", std::string("a stored Gaussian PDM: ") + e.what());
  }
  pdm::validateGaussians(out);
  return out;
}

}  // namespace rover::json
