#pragma once
// Gaussian PDM components as JSON: {"components": [{"x", "y", "sigma_x", "sigma_y",
// "rotation_deg", "weight"}]} (or the bare array). Positions and sigmas in metres, local frame.
#include <nlohmann/json.hpp>

#include "core/pdm/pdm.hpp"

namespace rover::json {

// Throws rover::Error (InvalidParameter) naming the field, e.g. "components[2].sigma_x".
std::vector<pdm::Gaussian> gaussiansFromJson(const nlohmann::json& j);
nlohmann::json toJson(const std::vector<pdm::Gaussian>& components);

}  // namespace rover::json
