#pragma once
// platemeter calibrate simulate PLAN.toml [-o DIR] [--format text|json]: the
// precision simulation of seed 000 section 4 (calib/precision_simulation.h,
// docs/precision-simulation.md). The plan's geometry is simulated noise-free by
// the lunar block simulator (samples/bundle_block.h) here, because calib may
// not include samples; the adjustment and the report are calib's.
#include <CLI/CLI.hpp>

#include "commands.h"
#include "platemeter/calib/precision_simulation.h"
#include "platemeter/samples/bundle_block.h"

namespace platemeter::cli {

// The plan's geometry as the lunar block simulator's options: the true lens,
// the orbits, the passpoints; sigma_um = 0 (no noise) and weight_sigma_um = the
// plan's image sigma. The rolls are those of the per-orbit sequence (the
// simulator's); SimulatePrecisionBlock turns them into the plan's sequence.
sim::LunarBlockOptions LunarBlockOptionsFromPlan(const PrecisionPlan& plan);

// The plan's noise-free block. With kappa_sequence = "continuous" every frame
// of orbit o (0-based) is turned about its optical axis by a further
// o * exposures_per_orbit * kappa_increment (exposure k of the whole sequence
// has kappa_start + k * increment) and its observations are projected again
// through the true camera; an observation that leaves the format is dropped,
// and so is a passpoint left with fewer than two rays (the summary says how
// many; none for a square format turned by multiples of 90 deg).
PrecisionBlock SimulatePrecisionBlock(const PrecisionPlan& plan);

// SimulatePrecisionBlock, then EvaluatePrecision.
PrecisionSimulationResult RunPrecisionSimulation(const PrecisionPlan& plan);

// Adds `simulate` to the `calibrate` command.
void RegisterCalibrateSimulate(CLI::App* calibrate, GlobalOptions& global);

}  // namespace platemeter::cli
