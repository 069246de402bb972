#pragma once
// An optional number as JSON: the value, or null (the reports' JSON files).
#include <optional>

#include <nlohmann/json.hpp>

namespace platemeter::calib_internal {

inline nlohmann::ordered_json OptionalJson(const std::optional<double>& value) {
  return value ? nlohmann::ordered_json(*value) : nlohmann::ordered_json(nullptr);
}

}  // namespace platemeter::calib_internal
