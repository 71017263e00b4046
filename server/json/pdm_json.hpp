#pragma once
// Gaussian PDM components as JSON: {"components": [{"x", "y", "sigma_x", "sigma_y",
// "rotation_deg", "weight"}]} (or the bare array). Positions and sigmas in metres, local frame.
#include <nlohmann/json.hpp>

#include "core/pdm/pdm.hpp"

namespace rover::json {

// Throws rover::Error (InvalidParameter) naming the field, e.g. "components[2].sigma_x".
std::vector<pdm::Gaussian> gaussiansFromJson(const nlohmann::json& j);
nlohmann::json toJson(const std::vector<pdm::Gaussian>& components);

// How a Gaussian PDM is stored (components.json, issue 22: its components instead of a raster of
// the whole map): every number as the double it is (rotation in radians), so the PDM discretised
// from the file is the one discretised when it was created, bit for bit.
//   {"format": "gaussians/1", "components": [{"x", "y", "sigma_x", "sigma_y", "rotation_rad", "weight"}]}
nlohmann::json toStoredJson(const std::vector<pdm::Gaussian>& components);
// Throws rover::Error (InvalidInput, field "components") on a file it cannot read.
std::vector<pdm::Gaussian> gaussiansFromStoredJson(const nlohmann::json& j);

}  // namespace rover::json
