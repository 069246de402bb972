// The precision simulation (calib/precision_simulation.h): the plan file
// (docs/precision-simulation.md: the documented example parses, every key
// reaches its field, errors name the line) and EvaluatePrecision on noise-free
// lunar blocks made here with samples/bundle_block.h. The comparison with seed
// 000's Tables 9 and 10 runs the sample plans end to end in
// tests/cli/cli_calibrate_simulate_test.cpp (the plan -> block step needs
// samples, which calib may not include: cli/cmd_calibrate_simulate.h).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

#include "platemeter/calib/precision_simulation.h"
#include "platemeter/core/error.h"
#include "platemeter/samples/bundle_block.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

std::string ReadTextOfPrecision(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The ```toml block of docs/precision-simulation.md.
std::string DocsExamplePrecision() {
  const std::string doc = ReadTextOfPrecision(std::string(PLATEMETER_SOURCE_DIR) + "/docs/precision-simulation.md");
  const size_t begin = doc.find("```toml\n");
  const size_t end = doc.find("```", begin + 8);
  if (begin == std::string::npos || end == std::string::npos) return "";
  return doc.substr(begin + 8, end - begin - 8);
}

// A noise-free block of the plan's geometry made directly with the simulator
// (the rolls as the simulator makes them: per orbit), and its PrecisionBlock.
PrecisionBlock BlockFor(const PrecisionPlan& plan) {
  sim::LunarBlockOptions o;
  o.camera.c_mm = plan.focal_length_mm;
  o.camera.xp_mm = o.camera.yp_mm = 0.0;
  o.camera.k1_per_mm2 = o.camera.k2_per_mm4 = o.camera.k3_per_mm6 = 0.0;
  o.camera.p1_per_mm = o.camera.p2_per_mm = 0.0;
  o.camera.format_width_mm = plan.format_width_mm;
  o.camera.format_height_mm = plan.format_height_mm;
  o.revolutions.clear();
  for (int k = 1; k <= plan.orbits; ++k) o.revolutions.push_back(k);
  o.kappa_increment_deg = plan.kappa_increment_deg;
  o.passpoints = plan.passpoints;
  o.sigma_um = 0.0;
  o.weight_sigma_um = plan.image_sigma_um;
  sim::SimulatedBlock block = sim::SimulateLunarBlock(o);
  PrecisionBlock out;
  out.input = block.input;
  for (const sim::StationTruth& s : block.truth.stations) {
    out.frame_orbit.push_back(s.group);
    out.frame_velocity.push_back(s.velocity_direction);
    out.frame_roll_deg.push_back(s.roll_deg);
  }
  out.summary = block.summary;
  return out;
}

// A small, fast plan: 80 mm, rolls per orbit (the simulator's), 60 passpoints.
PrecisionPlan SmallPlan() {
  PrecisionPlan plan;
  plan.title = "test";
  plan.kappa_sequence = KappaSequence::kPerOrbit;
  plan.passpoints = 60;
  return plan;
}

TEST(PrecisionPlan, DefaultsAreSeed000Section4) {
  const PrecisionPlan plan = ParsePrecisionPlan("", "empty.toml");
  EXPECT_EQ(plan.source, "empty.toml");
  EXPECT_DOUBLE_EQ(plan.focal_length_mm, 80.0);
  EXPECT_DOUBLE_EQ(plan.format_width_mm, 55.0);
  EXPECT_DOUBLE_EQ(plan.altitude_km, 108.5);
  EXPECT_EQ(plan.orbits, 3);
  EXPECT_EQ(plan.exposures_per_orbit, 3);
  EXPECT_DOUBLE_EQ(plan.convergence_deg, 80.0);
  EXPECT_DOUBLE_EQ(plan.kappa_increment_deg, 90.0);
  EXPECT_EQ(plan.kappa_sequence, KappaSequence::kContinuous);
  EXPECT_EQ(plan.passpoints, 215);
  EXPECT_EQ(plan.min_frames_per_point, 0);
  EXPECT_DOUBLE_EQ(plan.image_sigma_um, 15.0);
  // c, xp, yp, k1, p1, p2 free; k2, k3, b1, b2 held.
  const std::array<bool, kBundleCameraParams> free = {true, true, true, true, false, false, true, true, false, false};
  EXPECT_EQ(plan.free, free);
  EXPECT_EQ(plan.datum, PrecisionDatum::kAuto);
  EXPECT_EQ(plan.balance, RadialBalance::kAsGiven);
  EXPECT_NEAR(plan.CornerRadius_mm(), 38.89, 0.01);
}

TEST(PrecisionPlan, TheDocumentedExampleParses) {
  const std::string example = DocsExamplePrecision();
  ASSERT_FALSE(example.empty());
  const PrecisionPlan plan = ParsePrecisionPlan(example, "docs/precision-simulation.md");
  EXPECT_EQ(plan.title, "Seed 000 Table 9: 80 mm Hasselblad, 55 x 55 mm");
  EXPECT_EQ(plan.revolutions, (std::vector<int>{1, 2, 3}));
  ASSERT_EQ(plan.station_constraints.size(), 1u);
  EXPECT_EQ(plan.station_constraints[0].orbits, (std::vector<int>{1, 2}));
  ASSERT_TRUE(plan.station_constraints[0].sigma_angle_deg.has_value());
  EXPECT_EQ(plan.reference.source, "seed 000 Table 9, 80 mm");
  EXPECT_EQ(plan.reference.c_prime_um, 26.0);
  EXPECT_EQ(plan.radii_mm.size(), 9u);
}

TEST(PrecisionPlan, EveryKeyReachesItsField) {
  const std::string text = R"(
title = "every key"
[camera]
focal_length_mm = 150.5
format_width_mm = 60.0
format_height_mm = 50.0
xp_mm = 0.01
yp_mm = -0.02
k1_per_mm2 = 1e-5
k2_per_mm4 = 2e-9
k3_per_mm6 = 3e-12
p1_per_mm = 4e-6
p2_per_mm = 5e-6
[orbits]
body_radius_km = 1700.0
altitude_km = 100.0
track_spacing_km = 5.0
revolutions = [27, 28, 30, 31]
exposures_per_orbit = 4
convergence_deg = 60.0
kappa_start_deg = 45.0
kappa_increment_deg = -90.0
kappa_sequence = "per-orbit"
[passpoints]
count = 100
min_frames = 3
relief_m = 1000.0
format_margin_mm = 1.5
[errors]
image_sigma_um = 7.5
[adjustment]
free = ["c_mm", "k2", "b1"]
datum = "stations"
[[station_constraints]]
orbits = [2, 4]
sigma_in_track_m = 10.0
sigma_cross_track_m = 20.0
sigma_radial_m = 30.0
sigma_angle_deg = 0.1
[[station_constraints]]
sigma_in_track_m = 1.0
sigma_cross_track_m = 2.0
sigma_radial_m = 3.0
[report]
balance = "zero-at-radius"
balance_radius_mm = 25.0
radii_mm = [0, 10, 20]
correlation_threshold = 0.8
[reference]
source = "somewhere"
xp_um = 1
yp_um = 2
c_prime_um = 3
radial_corner_um = 4
decentering_corner_um = 5
[simulation]
seed = 42
)";
  const PrecisionPlan p = ParsePrecisionPlan(text, "every.toml");
  EXPECT_EQ(p.title, "every key");
  EXPECT_EQ(p.focal_length_mm, 150.5);
  EXPECT_EQ(p.format_width_mm, 60.0);
  EXPECT_EQ(p.format_height_mm, 50.0);
  EXPECT_EQ(p.xp_mm, 0.01);
  EXPECT_EQ(p.yp_mm, -0.02);
  EXPECT_EQ(p.k1_per_mm2, 1e-5);
  EXPECT_EQ(p.k2_per_mm4, 2e-9);
  EXPECT_EQ(p.k3_per_mm6, 3e-12);
  EXPECT_EQ(p.p1_per_mm, 4e-6);
  EXPECT_EQ(p.p2_per_mm, 5e-6);
  EXPECT_EQ(p.body_radius_km, 1700.0);
  EXPECT_EQ(p.altitude_km, 100.0);
  EXPECT_EQ(p.track_spacing_km, 5.0);
  EXPECT_EQ(p.revolutions, (std::vector<int>{27, 28, 30, 31}));
  EXPECT_EQ(p.orbits, 4);  // from the revolutions
  EXPECT_EQ(p.exposures_per_orbit, 4);
  EXPECT_EQ(p.convergence_deg, 60.0);
  EXPECT_EQ(p.kappa_start_deg, 45.0);
  EXPECT_EQ(p.kappa_increment_deg, -90.0);
  EXPECT_EQ(p.kappa_sequence, KappaSequence::kPerOrbit);
  EXPECT_EQ(p.passpoints, 100);
  EXPECT_EQ(p.min_frames_per_point, 3);
  EXPECT_EQ(p.relief_m, 1000.0);
  EXPECT_EQ(p.format_margin_mm, 1.5);
  EXPECT_EQ(p.image_sigma_um, 7.5);
  const std::array<bool, kBundleCameraParams> free = {true, false, false, false, true, false, false, false, true, false};
  EXPECT_EQ(p.free, free);
  EXPECT_EQ(p.datum, PrecisionDatum::kStations);
  ASSERT_EQ(p.station_constraints.size(), 2u);
  EXPECT_EQ(p.station_constraints[0].orbits, (std::vector<int>{2, 4}));
  EXPECT_EQ(p.station_constraints[0].sigma_in_track_m, 10.0);
  EXPECT_EQ(p.station_constraints[0].sigma_cross_track_m, 20.0);
  EXPECT_EQ(p.station_constraints[0].sigma_radial_m, 30.0);
  EXPECT_EQ(p.station_constraints[0].sigma_angle_deg, 0.1);
  EXPECT_TRUE(p.station_constraints[1].orbits.empty());
  EXPECT_FALSE(p.station_constraints[1].sigma_angle_deg.has_value());
  EXPECT_EQ(p.balance, RadialBalance::kZeroAtRadius);
  EXPECT_EQ(p.balance_radius_mm, 25.0);
  EXPECT_EQ(p.radii_mm, (std::vector<double>{0, 10, 20}));
  EXPECT_EQ(p.correlation_threshold, 0.8);
  EXPECT_EQ(p.reference.source, "somewhere");
  EXPECT_EQ(p.reference.xp_um, 1.0);
  EXPECT_EQ(p.reference.yp_um, 2.0);
  EXPECT_EQ(p.reference.c_prime_um, 3.0);
  EXPECT_EQ(p.reference.radial_corner_um, 4.0);
  EXPECT_EQ(p.reference.decentering_corner_um, 5.0);
  EXPECT_EQ(p.seed, 42u);
}

TEST(PrecisionPlan, BadPlansNameTheFileAndLine) {
  auto error_of = [](const std::string& text) -> std::string {
    try {
      ParsePrecisionPlan(text, "plan.toml");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of("[camera]\nfocal_length = 80\n").find("plan.toml: line 2: unknown key 'camera.focal_length'"),
            std::string::npos)
      << error_of("[camera]\nfocal_length = 80\n");
  EXPECT_NE(error_of("[orbit]\n").find("unknown key 'orbit'"), std::string::npos);
  EXPECT_NE(error_of("[camera]\nfocal_length_mm = -5\n").find("line 2"), std::string::npos);
  EXPECT_NE(error_of("[orbits]\ncount = 2\nrevolutions = [1, 2, 3]\n").find("names 3 orbits but 'count' = 2"),
            std::string::npos);
  EXPECT_NE(error_of("[orbits]\nkappa_sequence = \"spiral\"\n").find("kappa_sequence"), std::string::npos);
  EXPECT_NE(error_of("[adjustment]\nfree = [\"c\", \"q7\"]\n").find("unknown parameter 'q7'"), std::string::npos);
  EXPECT_NE(error_of("[adjustment]\ndatum = \"stations\"\n").find("needs [[station_constraints]]"), std::string::npos);
  EXPECT_NE(error_of("[adjustment]\ndatum = \"inner-constraints\"\n[[station_constraints]]\nsigma_in_track_m = 1\n"
                     "sigma_cross_track_m = 1\nsigma_radial_m = 1\n")
                .find("cannot be combined"),
            std::string::npos);
  EXPECT_NE(error_of("[passpoints]\nmin_frames = 1\n").find("min_frames"), std::string::npos);
  EXPECT_NE(error_of("[[station_constraints]]\nsigma_in_track_m = 1\nsigma_cross_track_m = 1\n").find("sigma_radial_m"),
            std::string::npos);
  EXPECT_NE(error_of("[[station_constraints]]\norbits = [4]\nsigma_in_track_m = 1\nsigma_cross_track_m = 1\n"
                     "sigma_radial_m = 1\n")
                .find("orbit 4"),
            std::string::npos);
  EXPECT_NE(error_of("[report]\nbalance = \"tilted\"\n").find("balance"), std::string::npos);
  EXPECT_NE(error_of("title = \n").find("plan.toml: line 1"), std::string::npos);  // TOML syntax
  EXPECT_THROW(ReadPrecisionPlan("/nonexistent/plan.toml"), Error);
}

// The sigmas the adjustment's covariance gives, and the bookkeeping around them.
TEST(PrecisionSimulation, AprioriSigmasOfANoiseFreeBlock) {
  const PrecisionPlan plan = SmallPlan();
  const PrecisionBlock block = BlockFor(plan);
  const PrecisionSimulationResult r = EvaluatePrecision(plan, block);
  SCOPED_TRACE(r.summary);
  ASSERT_TRUE(r.xp_um && r.yp_um && r.c_um);
  EXPECT_GT(*r.xp_um, 0.0);
  EXPECT_GT(*r.c_um, 0.0);
  // Degrees of freedom: 2 rows per image point less the unknowns (3 per
  // point, 6 per frame, 6 free camera parameters) less the datum's 7.
  EXPECT_EQ(r.frames, 9);
  EXPECT_EQ(r.points, 60);
  EXPECT_EQ(r.observations, 60 * 9);  // every passpoint in every frame (the common area)
  EXPECT_DOUBLE_EQ(r.dof, 2.0 * r.observations - (3.0 * r.points + 6.0 * r.frames + 6.0 - 7.0));
  EXPECT_EQ(r.rank.datum_defect, 7);
  EXPECT_EQ(r.rank.num_parameters, 6 * 9 + 6);
  EXPECT_EQ(r.rank.numerical_rank, r.rank.num_parameters - 7);
  EXPECT_EQ(r.prior_rows, 0);
  // Fixed parameters have no sigma; free ones do.
  for (int i = 0; i < kBundleCameraParams; ++i) {
    EXPECT_EQ(r.camera[i].sigma.has_value(), plan.free[i]) << r.camera[i].name;
  }
  // As given with a Gaussian lens: c' = c, delta_r'(corner) = k1 r^3, P = |p| r^2 (largest over directions).
  EXPECT_NEAR(r.calibrated_focal_length_mm.sigma * 1e3, *r.c_um, 1e-9 * *r.c_um);
  const double rc = r.corner_radius_mm;
  EXPECT_NEAR(r.radial_corner_sigma_um, *r.camera[3].sigma * rc * rc * rc * 1e3, 1e-6 * r.radial_corner_sigma_um);
  EXPECT_GE(r.decentering_corner_sigma_um * (1 + 1e-9), std::max(*r.camera[6].sigma, *r.camera[7].sigma) * rc * rc * 1e3);
  EXPECT_NEAR(r.profile.rows.back().r_mm, rc, 1e-12);
  EXPECT_EQ(r.correlation_names.size(), 6u);
  EXPECT_NEAR(r.correlation(0, 0), 1.0, 1e-12);
}

TEST(PrecisionSimulation, SigmasScaleWithTheErrorBudget) {
  PrecisionPlan plan = SmallPlan();
  const PrecisionSimulationResult a = EvaluatePrecision(plan, BlockFor(plan));
  plan.image_sigma_um = 7.5;
  const PrecisionSimulationResult b = EvaluatePrecision(plan, BlockFor(plan));
  EXPECT_NEAR(*b.xp_um, 0.5 * *a.xp_um, 1e-6 * *a.xp_um);
  EXPECT_NEAR(*b.c_um, 0.5 * *a.c_um, 1e-6 * *a.c_um);
  EXPECT_NEAR(b.radial_corner_sigma_um, 0.5 * a.radial_corner_sigma_um, 1e-6 * a.radial_corner_sigma_um);
  EXPECT_NEAR(b.decentering_corner_sigma_um, 0.5 * a.decentering_corner_sigma_um, 1e-6 * a.decentering_corner_sigma_um);
}

TEST(PrecisionSimulation, ABalanceAtARadiusIsZeroThere) {
  PrecisionPlan plan = SmallPlan();
  plan.balance = RadialBalance::kZeroAtRadius;
  plan.balance_radius_mm = 30.0;
  plan.radii_mm = {0, 10, 20, 30, 35};
  const PrecisionSimulationResult r = EvaluatePrecision(plan, BlockFor(plan));
  ASSERT_EQ(r.profile.rows.size(), 6u);  // the corner added
  EXPECT_NEAR(r.profile.rows[3].radial_sigma_um, 0.0, 1e-9);
  // sigma(delta_r'(r)) = sigma(k1) r (r^2 - R^2) with k1 alone (the lens is distortion-free).
  const double rc = r.corner_radius_mm;
  EXPECT_NEAR(r.radial_corner_sigma_um, *r.camera[3].sigma * rc * (rc * rc - 900.0) * 1e3, 1e-6 * r.radial_corner_sigma_um);
  // c' = c / (1 + k1 R^2) carries the k1 term: differs from sigma(c).
  EXPECT_NE(r.calibrated_focal_length_mm.sigma * 1e3, *r.c_um);
}

TEST(PrecisionSimulation, StationConstraintsFixTheDatum) {
  PrecisionPlan plan = SmallPlan();
  const PrecisionBlock block = BlockFor(plan);
  const PrecisionSimulationResult free_network = EvaluatePrecision(plan, block);
  StationConstraint c;
  c.orbits = {1, 2};
  c.sigma_in_track_m = c.sigma_cross_track_m = c.sigma_radial_m = 10.0;
  plan.station_constraints.push_back(c);
  const PrecisionSimulationResult constrained = EvaluatePrecision(plan, block);
  SCOPED_TRACE(constrained.summary);
  EXPECT_EQ(constrained.rank.datum_defect, 0);
  EXPECT_EQ(constrained.rank.numerical_rank, constrained.rank.num_parameters);
  EXPECT_EQ(constrained.prior_rows, 6 * 3);  // 6 stations x 3 coordinates
  EXPECT_DOUBLE_EQ(constrained.dof, free_network.dof + 18.0 - 7.0);
  EXPECT_NE(constrained.datum_words.find("6 of 9 frames"), std::string::npos);
  // More information never hurts.
  EXPECT_LE(*constrained.c_um, *free_network.c_um * (1 + 1e-9));
  EXPECT_LE(*constrained.xp_um, *free_network.xp_um * (1 + 1e-9));
  // Two tables on one orbit is an error.
  plan.station_constraints.push_back(c);
  EXPECT_THROW(EvaluatePrecision(plan, block), Error);
}

TEST(PrecisionSimulation, ABlockThatDoesNotMatchThePlanIsAnError) {
  const PrecisionPlan plan = SmallPlan();
  PrecisionBlock block = BlockFor(plan);
  block.frame_orbit.pop_back();
  EXPECT_THROW(EvaluatePrecision(plan, block), Error);
  block = BlockFor(plan);
  block.frame_orbit[0] = 7;  // the plan has 3 orbits
  EXPECT_THROW(EvaluatePrecision(plan, block), Error);
}

TEST(PrecisionSimulation, TextAndJsonReports) {
  PrecisionPlan plan = SmallPlan();
  plan.reference.source = "somewhere, Table 0";
  plan.reference.xp_um = 10.0;
  plan.reference.c_prime_um = 20.0;
  const PrecisionSimulationResult r = EvaluatePrecision(plan, BlockFor(plan));
  const std::string text = FormatPrecisionText(r);
  for (const char* s : {"A-priori standard deviations (sigma0 = 1)", "somewhere, Table 0", "ratio",
                        "delta_r' at the corner (r = 38.9 mm)", "P(r) at the corner", "degrees of freedom (sigma0)",
                        "datum defect 7", "k1_per_mm2"}) {
    EXPECT_NE(text.find(s), std::string::npos) << s << "\n" << text;
  }
  const nlohmann::json j = nlohmann::json::parse(FormatPrecisionJson(r));
  EXPECT_EQ(j["kind"], "precision-simulation");
  EXPECT_NEAR(j["sigma_apriori"]["xp_um"].get<double>(), *r.xp_um, 1e-9);
  EXPECT_NEAR(j["sigma_apriori"]["c_prime_um"].get<double>(), r.calibrated_focal_length_mm.sigma * 1e3, 1e-9);
  EXPECT_EQ(j["reference"]["xp_um"], 10.0);
  EXPECT_EQ(j["dof"].get<double>(), r.dof);
  EXPECT_EQ(j["rank"]["datum_defect"], 7);
  EXPECT_EQ(j["camera"].size(), static_cast<size_t>(kBundleCameraParams));
  EXPECT_TRUE(j["camera"][4]["sigma_apriori"].is_null());  // k2 held
  EXPECT_EQ(j["profile"].back()["r_mm"].get<double>(), r.corner_radius_mm);

  testing::TempDir dir;
  const std::vector<std::string> written = WritePrecisionOutputs(dir.file("out"), r);
  ASSERT_EQ(written.size(), 2u);
  EXPECT_EQ(ReadTextOfPrecision(written[0]), FormatPrecisionJson(r));
  EXPECT_EQ(ReadTextOfPrecision(written[1]), text);
}

}  // namespace
}  // namespace platemeter
