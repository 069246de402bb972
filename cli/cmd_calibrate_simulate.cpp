// platemeter calibrate simulate: the precision simulation of a planned
// geometry (cmd_calibrate_simulate.h, docs/precision-simulation.md).
#include "cmd_calibrate_simulate.h"

#include <cmath>
#include <iostream>
#include <map>
#include <memory>

#include <fmt/format.h>

#include "platemeter/core/output_set.h"
#include "platemeter/core/error.h"

namespace platemeter::cli {
namespace {

struct SimulateArgs {
  std::string plan;
  std::string output_dir;
  std::string format = "text";
};

void RunSimulate(const SimulateArgs& args) {
  if (args.format != "text" && args.format != "json") {
    throw Error("--format", "must be text or json (is '" + args.format + "')");
  }
  const PrecisionPlan plan = ReadPrecisionPlan(args.plan);
  const PrecisionSimulationResult result = RunPrecisionSimulation(plan);
  std::cout << (args.format == "json" ? FormatPrecisionJson(result) : FormatPrecisionText(result));
  if (!args.output_dir.empty()) {
    for (const std::string& path : WritePrecisionOutputs(args.output_dir, result)) std::cerr << "wrote " << path << '\n';
  }
}

}  // namespace

sim::LunarBlockOptions LunarBlockOptionsFromPlan(const PrecisionPlan& plan) {
  sim::LunarBlockOptions o;
  o.camera.c_mm = plan.focal_length_mm;
  o.camera.xp_mm = plan.xp_mm;
  o.camera.yp_mm = plan.yp_mm;
  o.camera.k1_per_mm2 = plan.k1_per_mm2;
  o.camera.k2_per_mm4 = plan.k2_per_mm4;
  o.camera.k3_per_mm6 = plan.k3_per_mm6;
  o.camera.p1_per_mm = plan.p1_per_mm;
  o.camera.p2_per_mm = plan.p2_per_mm;
  o.camera.b1 = 0.0;
  o.camera.b2 = 0.0;
  o.camera.format_width_mm = plan.format_width_mm;
  o.camera.format_height_mm = plan.format_height_mm;
  o.moon_radius_m = plan.body_radius_km * 1e3;
  o.altitude_m = plan.altitude_km * 1e3;
  o.revolutions = plan.revolutions;
  if (o.revolutions.empty()) {
    o.revolutions.clear();
    for (int k = 1; k <= plan.orbits; ++k) o.revolutions.push_back(k);
  }
  o.track_spacing_m = plan.track_spacing_km * 1e3;
  o.exposures_per_orbit = plan.exposures_per_orbit;
  o.convergence_deg = plan.convergence_deg;
  o.kappa_start_deg = plan.kappa_start_deg;
  o.kappa_increment_deg = plan.kappa_increment_deg;
  o.rolls_continue_across_orbits = plan.kappa_sequence == KappaSequence::kContinuous;
  o.passpoints = plan.passpoints;
  o.min_frames_per_point = plan.min_frames_per_point;
  o.relief_m = plan.relief_m;
  o.format_margin_mm = plan.format_margin_mm;
  o.sigma_um = 0.0;
  o.weight_sigma_um = plan.image_sigma_um;
  o.approximations = sim::ApproximationOptions{};  // start at the truth
  o.seed = plan.seed;
  return o;
}

PrecisionBlock SimulatePrecisionBlock(const PrecisionPlan& plan) {
  std::string why;
  if (!plan.Check(&why)) throw Error(plan.source.empty() ? "precision plan" : plan.source, why);
  sim::SimulatedBlock block = sim::SimulateLunarBlock(LunarBlockOptionsFromPlan(plan));
  PrecisionBlock out;
  out.input = std::move(block.input);
  for (const sim::StationTruth& s : block.truth.stations) {
    out.frame_orbit.push_back(s.group);
    out.frame_velocity.push_back(s.velocity_direction);
    out.frame_roll_deg.push_back(s.roll_deg);
  }
  out.summary = block.summary;
  // The simulator states the noise it added (none): say what the weights are.
  const size_t noise = out.summary.find(", sigma 0.0 um");
  if (noise != std::string::npos) {
    out.summary.replace(noise, 14, fmt::format(", noise-free, weighted by {:g} um", plan.image_sigma_um));
  }
  return out;
}

PrecisionSimulationResult RunPrecisionSimulation(const PrecisionPlan& plan) {
  return EvaluatePrecision(plan, SimulatePrecisionBlock(plan));
}

void RegisterCalibrateSimulate(CLI::App* calibrate, GlobalOptions& global) {
  (void)global;
  auto args = std::make_shared<SimulateArgs>();
  auto* cmd = calibrate->add_subcommand(
      "simulate",
      "precision simulation (seed 000 section 4): the a-priori sigmas of a planned geometry, without images "
      "(docs/precision-simulation.md)");
  cmd->add_option("PLAN", args->plan, "the plan (TOML), e.g. samples/plans/seed000-table9-80mm.toml")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", args->output_dir, "also write precision.json and precision.txt into this folder");
  cmd->add_option("--format", args->format, "what to print: text or json")
      ->check(CLI::IsMember({"text", "json"}))
      ->capture_default_str();
  cmd->callback([args] {
    InstallOutputSetInterruptCleanup();
    RunSimulate(*args);
  });
}

}  // namespace platemeter::cli
