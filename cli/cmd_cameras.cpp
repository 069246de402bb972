// platemeter cameras profile NAME: seed 000's distortion products of a
// camera's lens calibration (balanced radial distortion, eq. 14, with its
// calibrated focal length; decentering profile, eq. 15; phase angle, eq. 16)
// with first-order sigmas (calib/distortion_profile.h, docs/cameras.md).
// `cameras list` and `cameras show` live in cmd_grids.cpp; this adds `profile`
// to the same `cameras` command.
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cmd_cameras_export.h"
#include "commands.h"
#include "platemeter/calib/distortion_profile.h"
#include "platemeter/calib/model_conversion.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"

namespace platemeter::cli {
namespace {

struct ProfileArguments {
  std::string camera;
  double balance_radius_mm = std::nan("");
  bool equal_lobes = false;
  bool equal_areas = false;
  double max_radius_mm = std::nan("");
  std::string radii_mm;                   // "0,5,10"; empty: from the format
  std::vector<std::string> correlations;  // "NAME1,NAME2=RHO"
  std::string format = "text";
};

std::string Trim(const std::string& text) {
  const size_t begin = text.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  const size_t end = text.find_last_not_of(" \t");
  return text.substr(begin, end - begin + 1);
}

// A whole number, or an Error naming the option.
double ParseNumber(const std::string& text, const std::string& option) {
  const std::string trimmed = Trim(text);
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(trimmed, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (trimmed.empty() || used != trimmed.size() || !std::isfinite(value)) {
    throw Error(option, fmt::format("'{}' is not a number", trimmed));
  }
  return value;
}

std::vector<double> ParseRadii(const std::string& text) {
  std::vector<double> radii;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    const double r = ParseNumber(item, "--radii-mm");
    if (r < 0.0) throw Error("--radii-mm", fmt::format("a radius must be >= 0 mm (is {:g})", r));
    radii.push_back(r);
  }
  if (radii.empty()) throw Error("--radii-mm", "no radii (give e.g. 0,5,10,15,20,25,30,35,39)");
  return radii;
}

void ApplyCorrelation(const std::string& text, LensEstimate* lens) {
  const size_t equals = text.find('=');
  const size_t comma = text.find(',');
  if (equals == std::string::npos || comma == std::string::npos || comma > equals) {
    throw Error("--correlation", fmt::format("'{}' is not NAME1,NAME2=RHO", text));
  }
  const std::string a = Trim(text.substr(0, comma));
  const std::string b = Trim(text.substr(comma + 1, equals - comma - 1));
  const double rho = ParseNumber(text.substr(equals + 1), "--correlation");
  try {
    SetCorrelation(lens, a, b, rho);
  } catch (const Error& error) {
    throw Error("--correlation", error.reason());
  }
}

// Fixed-point text without a negative zero ("-0.0" for -0.04 is "0.0").
std::string Fixed(double value, int decimals) {
  std::string text = fmt::format("{:.{}f}", value, decimals);
  if (text.find_first_not_of("-0.") == std::string::npos && text[0] == '-') text.erase(0, 1);
  return text;
}

std::string PlusMinus(const ValueWithSigma& v, const char* value_format, const char* sigma_format) {
  return fmt::format(fmt::runtime(value_format), v.value) + " +- " + fmt::format(fmt::runtime(sigma_format), v.sigma);
}

void PrintProfile(const std::string& camera_name, const CameraDefinition& camera, const DistortionProfile& profile,
                  const std::string& format) {
  const LensCalibration& lens = *camera.lens;
  std::string balance;
  switch (profile.balance) {
    case RadialBalance::kAsGiven:
      balance = "as given (the lens's own k0' and c')";
      break;
    case RadialBalance::kZeroAtRadius:
      balance = fmt::format("zero at r = {:g} mm", profile.balance_radius_mm);
      break;
    case RadialBalance::kEqualLobePeaks:
      balance = fmt::format("equal positive and negative lobe peaks over 0..{:g} mm", profile.max_radius_mm);
      break;
    case RadialBalance::kEqualLobeAreas:
      balance = fmt::format("equal positive and negative lobe areas over 0..{:g} mm", profile.max_radius_mm);
      break;
  }
  const double deg = 180.0 / M_PI;
  const ValueWithSigma phase = {profile.phase_angle_rad.value * deg, profile.phase_angle_rad.sigma * deg};
  const auto& k = profile.radial_coefficients;
  const std::vector<std::pair<std::string, std::string>> header = {
      {"camera", camera_name},
      {"lens", fmt::format("{} ({})", lens.model, lens.source)},
      {"balance", balance},
      {"c_prime_mm", PlusMinus(profile.calibrated_focal_length_mm, "{:.4f}", "{:.4f}")},
      {"radial", fmt::format("k0' = {}, k1' = {} /mm^2, k2' = {} /mm^4, k3' = {} /mm^6",
                             PlusMinus(k[0], "{:.6e}", "{:.2e}"), PlusMinus(k[1], "{:.6e}", "{:.2e}"),
                             PlusMinus(k[2], "{:.6e}", "{:.2e}"), PlusMinus(k[3], "{:.6e}", "{:.2e}"))},
      {"decentering", fmt::format("J1 = {} /mm, J2 = {} /mm^3", PlusMinus(profile.decentering_j1_per_mm, "{:.4e}", "{:.2e}"),
                                  PlusMinus(profile.decentering_j2_per_mm3, "{:.4e}", "{:.2e}"))},
      {"phase_angle_deg", std::isnan(phase.value) ? std::string("undefined (no decentering)")
                                                  : PlusMinus(phase, "{:.1f}", "{:.1f}")},
  };
  if (format == "csv") {
    for (const auto& [key, value] : header) std::cout << "# " << key << ": " << value << '\n';
    std::cout << "r_mm,radial_um,radial_sigma_um,decentering_um,decentering_sigma_um\n";
    for (const DistortionProfileRow& row : profile.rows) {
      std::cout << fmt::format("{:g},{},{},{},{}\n", row.r_mm, Fixed(row.radial_um, 4), Fixed(row.radial_sigma_um, 4),
                               Fixed(row.decentering_um, 4), Fixed(row.decentering_sigma_um, 4));
    }
    return;
  }
  for (const auto& [key, value] : header) std::cout << fmt::format("{:<17}{}\n", key + ":", value);
  std::cout << '\n'
            << fmt::format("{:>8} {:>10} {:>16} {:>15} {:>21}\n", "r_mm", "radial_um", "radial_sigma_um",
                           "decentering_um", "decentering_sigma_um");
  for (const DistortionProfileRow& row : profile.rows) {
    std::cout << fmt::format("{:>8g} {:>10} {:>16} {:>15} {:>21}\n", row.r_mm, Fixed(row.radial_um, 1),
                             Fixed(row.radial_sigma_um, 1), Fixed(row.decentering_um, 1),
                             Fixed(row.decentering_sigma_um, 1));
  }
}

void RunProfile(const GlobalOptions& global, const ProfileArguments& args) {
  const DefinitionRegistry registry = DefinitionRegistry::Load(global.definition_files);
  const CameraDefinition& camera = registry.Camera(args.camera);  // throws for an unknown name
  if (!camera.lens) {
    throw Error(args.camera, "the camera definition has no lens calibration ([camera.lens]) to profile");
  }
  std::vector<std::string> without_sigma;
  LensEstimate lens = LensEstimateFromCalibration(*camera.lens, args.camera, &without_sigma);
  for (const std::string& correlation : args.correlations) ApplyCorrelation(correlation, &lens);

  DistortionProfileOptions options;
  const double half_diagonal_mm = FormatHalfDiagonal_mm(camera.format_width_mm, camera.format_height_mm);
  options.radii_mm = args.radii_mm.empty() ? DefaultProfileRadii_mm(camera.format_width_mm, camera.format_height_mm)
                                           : ParseRadii(args.radii_mm);
  options.max_radius_mm = std::isnan(args.max_radius_mm) ? half_diagonal_mm : args.max_radius_mm;
  if (!std::isnan(args.max_radius_mm) && !args.equal_lobes && !args.equal_areas) {
    throw Error("--max-radius-mm", "is the range of --equal-lobes or --equal-areas; give one of them");
  }
  if (!std::isnan(args.balance_radius_mm)) {
    options.balance = RadialBalance::kZeroAtRadius;
    options.balance_radius_mm = args.balance_radius_mm;
  } else if (args.equal_lobes) {
    options.balance = RadialBalance::kEqualLobePeaks;
  } else if (args.equal_areas) {
    options.balance = RadialBalance::kEqualLobeAreas;
  }
  std::string why;
  if (!options.Check(&why)) throw Error(args.camera, why);
  DistortionProfile profile;
  try {
    profile = ComputeDistortionProfile(lens, options);
  } catch (const Error& error) {
    throw Error(args.camera, error.reason());
  }
  for (const std::string& name : without_sigma) {
    std::cerr << "platemeter: warning: " << args.camera << ": no sigma for " << name
              << " in the definition; taken as exact\n";
  }
  PrintProfile(args.camera, camera, profile, args.format);
}

}  // namespace

void RegisterCamerasCommand(CLI::App& app, GlobalOptions& global) {
  // `cameras` (list, show) may already be registered by cmd_grids.cpp.
  CLI::App* cameras = nullptr;
  try {
    cameras = app.get_subcommand("cameras");
  } catch (const CLI::OptionNotFound&) {
    cameras = app.add_subcommand("cameras", "camera definitions (format, grid, fiducials, lens calibration)");
    cameras->require_subcommand(1);
  }

  auto args = std::make_shared<ProfileArguments>();
  auto* profile = cameras->add_subcommand(
      "profile",
      "the lens's balanced radial distortion (seed 000 eq. 14) and calibrated focal length, decentering profile "
      "(eq. 15) and phase angle (eq. 16), with first-order sigmas (docs/cameras.md)");
  profile->add_option("NAME", args->camera, "camera name (see `platemeter cameras list`)")->required();
  auto* radius = profile->add_option("--balance-radius-mm", args->balance_radius_mm,
                                     "balance the radial distortion to zero at this radius (seed 000: 30)");
  auto* lobes = profile->add_flag("--equal-lobes", args->equal_lobes,
                                  "balance to equal positive and negative lobe peaks over 0..--max-radius-mm (minimax)");
  auto* areas = profile->add_flag("--equal-areas", args->equal_areas,
                                  "balance to equal lobe areas over 0..--max-radius-mm (seed 001 Fig. 8's wording)");
  radius->excludes(lobes)->excludes(areas);
  lobes->excludes(areas);
  profile->add_option("--max-radius-mm", args->max_radius_mm,
                      "the range of the equal lobes, mm (default: the format's half diagonal)");
  profile->add_option("--radii-mm", args->radii_mm,
                      "comma-separated table radii in mm (default: 0 to the format's half diagonal)");
  profile->add_option("--correlation", args->correlations,
                      "NAME1,NAME2=RHO: a correlation the definition's sigmas do not carry (repeatable), e.g. "
                      "k1_per_mm2,k2_per_mm4=-0.96");
  profile->add_option("--format", args->format, "text (default) or csv")->check(CLI::IsMember({"text", "csv"}));
  profile->callback([&global, args] { RunProfile(global, *args); });
  RegisterCamerasExport(cameras, global);
}

}  // namespace platemeter::cli
