#pragma once
// Angle and Gaussian constants shared by every layer (one definition, so that no two
// files of a library define their own: the unity build, cmake/platemeter_library.cmake,
// compiles several files as one).
#include <numbers>

namespace platemeter {

inline constexpr double kRadPerDeg = std::numbers::pi / 180.0;
inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;
inline constexpr double kRadPerArcsec = std::numbers::pi / 648000.0;
inline constexpr double kArcsecPerRad = 648000.0 / std::numbers::pi;
inline constexpr double kInvSqrt2 = 0.70710678118654752440;
inline constexpr double kInvSqrt2Pi = 0.39894228040143267794;  // the unit normal density's peak

}  // namespace platemeter
