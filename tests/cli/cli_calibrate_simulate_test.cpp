// platemeter calibrate simulate (cli/cmd_calibrate_simulate.h): the precision
// simulation of seed 000 section 4 run end to end from the sample plans
// (samples/plans/*.toml) and compared with the paper's Tables 9 and 10, the
// section 3 reductions as a check of the machinery, the roll sequences, and
// the subcommand itself (registered on a `calibrate` command built here).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

#include "cmd_calibrate_simulate.h"
#include "platemeter/core/error.h"
#include "support/test_support.h"

namespace platemeter::cli {
namespace {

std::string PlanPath(const std::string& name) { return std::string(PLATEMETER_SOURCE_DIR) + "/samples/plans/" + name; }

std::string ReadTextOfSimulate(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Published standard deviations (um) of one row.
struct PaperRow {
  const char* plan;
  double xp_um, yp_um, c_prime_um, radial_corner_um, decentering_corner_um;
};

// Seed 000 section 4, Table 9 ("Results of Simulated Self-calibration For
// Various Hasselblad Cameras": standard deviations of xp, yp, c', and of
// delta_r' and P_r at the corner of the 55 x 55 mm format, um).
constexpr PaperRow kTable9[] = {
    {"seed000-table9-50mm.toml", 9, 6, 14, 15, 2},
    {"seed000-table9-80mm.toml", 21, 14, 26, 13, 2},
    {"seed000-table9-150mm.toml", 70, 44, 70, 12, 2},
    {"seed000-table9-500mm.toml", 740, 460, 701, 12, 2},
};
// Seed 000 section 4, Table 10 ("Results of Simulated Self-calibration For the
// Lunar Terrain Camera", um; delta_r' and P_r at the corner of the format).
constexpr PaperRow kTable10 = {"seed000-table10-terrain.toml", 2, 2, 3, 6, 1};

// ratio = predicted / paper within [1 / factor, factor].
void ExpectWithin(const char* what, double predicted, double paper, double factor) {
  const double ratio = predicted / paper;
  EXPECT_LE(ratio, factor) << what << ": platemeter " << predicted << " um, paper " << paper << " um";
  EXPECT_GE(ratio, 1.0 / factor) << what << ": platemeter " << predicted << " um, paper " << paper << " um";
}

PrecisionSimulationResult RunPlan(const std::string& name) {
  return RunPrecisionSimulation(ReadPrecisionPlan(PlanPath(name)));
}

void ExpectRow(const PaperRow& row, double factor, double yp_factor) {
  const PrecisionSimulationResult r = RunPlan(row.plan);
  SCOPED_TRACE(std::string(row.plan) + ": " + r.summary);
  ASSERT_TRUE(r.xp_um && r.yp_um && r.c_um);
  ExpectWithin("xp", *r.xp_um, row.xp_um, factor);
  ExpectWithin("yp", *r.yp_um, row.yp_um, yp_factor);
  ExpectWithin("c'", r.calibrated_focal_length_mm.sigma * 1e3, row.c_prime_um, factor);
  ExpectWithin("delta_r' at the corner", r.radial_corner_sigma_um, row.radial_corner_um, factor);
  ExpectWithin("P at the corner", r.decentering_corner_sigma_um, row.decentering_corner_um, factor);
  // The geometry of section 4: 9 frames, 215 passpoints in all of them, the
  // datum's 7 similarity directions and nothing else in the null space.
  EXPECT_EQ(r.frames, 9);
  EXPECT_EQ(r.points, 215);
  EXPECT_EQ(r.observations, 215 * 9);
  EXPECT_EQ(r.dof, 3172.0);
  EXPECT_EQ(r.rank.datum_defect, 7);
  EXPECT_EQ(r.rank.numerical_rank, r.rank.num_parameters - 7);
  for (const NullDirection& d : r.rank.directions) EXPECT_FALSE(d.exact) << d.words;
  // The plan carries the same published values for the report.
  const PrecisionReference& ref = r.plan.reference;
  EXPECT_EQ(ref.xp_um, row.xp_um);
  EXPECT_EQ(ref.yp_um, row.yp_um);
  EXPECT_EQ(ref.c_prime_um, row.c_prime_um);
  EXPECT_EQ(ref.radial_corner_um, row.radial_corner_um);
  EXPECT_EQ(ref.decentering_corner_um, row.decentering_corner_um);
}

// The bar: within a factor 2 of Table 9 (yp 3: the paper's geometry is
// under-specified, docs/precision-simulation.md "Investigation").
TEST(CalibrateSimulate, Seed000Table9Hasselblads) {
  for (const PaperRow& row : kTable9) ExpectRow(row, 2.0, 3.0);
}

// Within 1.5 of Table 10, yp included.
TEST(CalibrateSimulate, Seed000Table10TerrainCamera) { ExpectRow(kTable10, 1.5, 1.5); }

// The reading the first run used -- rolls 0, 90, 180 deg in every
// orbit -- misses Table 9 by a factor 3 and more (docs: "Investigation"); the
// continuous sequence of Fig. 3 is what reaches it.
TEST(CalibrateSimulate, RollsRestartingOnEveryOrbitMissTable9) {
  PrecisionPlan plan = ReadPrecisionPlan(PlanPath("seed000-table9-80mm.toml"));
  plan.kappa_sequence = KappaSequence::kPerOrbit;
  const PrecisionSimulationResult r = RunPrecisionSimulation(plan);
  EXPECT_GT(*r.xp_um / 21.0, 3.0);
  EXPECT_GT(*r.yp_um / 14.0, 3.0);
  EXPECT_GT(*r.c_um / 26.0, 2.5);
  EXPECT_EQ(r.frame_roll_deg, (std::vector<double>{0, 90, 180, 0, 90, 180, 0, 90, 180}));
}

TEST(CalibrateSimulate, ContinuousRollsTurnEveryExposureBy90Degrees) {
  const PrecisionPlan plan = ReadPrecisionPlan(PlanPath("seed000-table9-80mm.toml"));
  const PrecisionBlock block = SimulatePrecisionBlock(plan);
  EXPECT_EQ(block.frame_roll_deg, (std::vector<double>{0, 90, 180, -90, 0, 90, 180, -90, 0}));
  EXPECT_EQ(block.frame_orbit, (std::vector<int>{0, 0, 0, 1, 1, 1, 2, 2, 2}));
  // A square format turned by multiples of 90 deg keeps every passpoint in every frame.
  EXPECT_EQ(block.input.observations.size(), 215u * 9u);
  EXPECT_EQ(block.input.ground_points.size(), 215u);
  for (const ImageObservation& o : block.input.observations) {
    EXPECT_LE(std::abs(o.x_mm), 27.0);
    EXPECT_LE(std::abs(o.y_mm), 27.0);
    EXPECT_DOUBLE_EQ(o.sigma_x_mm, 0.015);
  }
  const sim::LunarBlockOptions options = LunarBlockOptionsFromPlan(plan);
  EXPECT_EQ(options.sigma_um, 0.0);  // noise-free
  EXPECT_EQ(options.weight_sigma_um, 15.0);
  EXPECT_EQ(options.revolutions, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(options.track_spacing_m, 8500.0);
}

// Seed 000 section 3 (real data, a posteriori sigmas): the simulation of the
// flown Apollo 14 geometry lands within a factor 2 of Tables 1-4.
TEST(CalibrateSimulate, Seed000Section3Apollo14) {
  // Table 1: c' +- 2.060 mm; Table 2 at r = 39 mm: delta_r' +- 11 um, P +- 5 um.
  const PrecisionSimulationResult pure = RunPlan("seed000-section3-apollo14.toml");
  SCOPED_TRACE(pure.summary);
  EXPECT_FALSE(pure.xp_um.has_value());  // held at zero, as in section 3.2
  ExpectWithin("c'", pure.calibrated_focal_length_mm.sigma * 1e3, 2060.0, 2.0);
  ExpectWithin("delta_r'", pure.radial_corner_sigma_um, 11.0, 2.0);
  ExpectWithin("P", pure.decentering_corner_sigma_um, 5.0, 2.0);
  EXPECT_EQ(pure.rank.datum_defect, 7);
  // Table 3: c' +- 1.503 mm; Table 4 at 39 mm: +- 11 um, +- 4 um. The
  // constraints on revolutions 27 and 28 are the datum.
  const PrecisionSimulationResult constrained = RunPlan("seed000-section3-constrained.toml");
  SCOPED_TRACE(constrained.summary);
  ExpectWithin("c'", constrained.calibrated_focal_length_mm.sigma * 1e3, 1503.0, 2.0);
  ExpectWithin("delta_r'", constrained.radial_corner_sigma_um, 11.0, 2.0);
  ExpectWithin("P", constrained.decentering_corner_sigma_um, 4.0, 2.0);
  EXPECT_EQ(constrained.rank.datum_defect, 0);
  EXPECT_EQ(constrained.prior_rows, 18);
}

// The subcommand, parsed as main() would (the binary registers it through
// cmd_calibrate.cpp).
struct CommandOutput {
  std::string out;
};

CommandOutput RunCommand(const std::vector<std::string>& args) {
  CLI::App app;
  GlobalOptions global;
  auto* calibrate = app.add_subcommand("calibrate", "");
  RegisterCalibrateSimulate(calibrate, global);
  std::vector<std::string> reversed(args.rbegin(), args.rend());
  std::ostringstream captured;
  std::streambuf* old = std::cout.rdbuf(captured.rdbuf());
  try {
    app.parse(reversed);
  } catch (...) {
    std::cout.rdbuf(old);
    throw;
  }
  std::cout.rdbuf(old);
  return {captured.str()};
}

TEST(CalibrateSimulate, CommandPrintsTextOrJsonAndWritesOutputs) {
  const std::string plan = PlanPath("seed000-table10-terrain.toml");
  const CommandOutput text = RunCommand({"calibrate", "simulate", plan});
  EXPECT_NE(text.out.find("seed 000 Table 10"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("A-priori standard deviations (sigma0 = 1)"), std::string::npos);

  testing::TempDir dir;
  const CommandOutput json = RunCommand({"calibrate", "simulate", plan, "--format", "json", "-o", dir.file("out")});
  const nlohmann::json j = nlohmann::json::parse(json.out);
  EXPECT_EQ(j["kind"], "precision-simulation");
  EXPECT_EQ(j["reference"]["xp_um"], 2.0);
  EXPECT_EQ(j["dof"], 3172.0);
  EXPECT_EQ(ReadTextOfSimulate(dir.file("out/precision.json")), json.out);
  EXPECT_NE(ReadTextOfSimulate(dir.file("out/precision.txt")).find("Distortion profiles"), std::string::npos);

  EXPECT_THROW(RunCommand({"calibrate", "simulate", plan, "--format", "yaml"}), CLI::ParseError);
  EXPECT_THROW(RunCommand({"calibrate", "simulate", dir.file("missing.toml")}), CLI::ParseError);
  std::ofstream(dir.file("bad.toml")) << "[orbits]\naltitude = 100\n";
  try {
    RunCommand({"calibrate", "simulate", dir.file("bad.toml")});
    ADD_FAILURE() << "a misspelt key must fail";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("line 2: unknown key 'orbits.altitude'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace platemeter::cli
