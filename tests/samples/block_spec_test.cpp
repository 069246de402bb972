// The block spec and the block's layout (docs/block-simulator.md): the bundled
// block reads with every key arriving; mistakes are Errors naming the file, the
// line and the key; the layout puts every point where the true camera projects
// it (the distortion once), and the plate simulator carries those positions to
// the scan without another lens.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "platemeter/calib/camera_model.h"
#include "platemeter/calib/distortion_models.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/samples/block_render.h"
#include "platemeter/samples/block_spec.h"
#include "support/test_support.h"

namespace platemeter::sim {
namespace {

using ::testing::HasSubstr;

std::string BlocksDir() { return std::string(PLATEMETER_SOURCE_DIR) + "/samples/blocks"; }
std::string BundledBlock() { return BlocksDir() + "/hasselblad-block.toml"; }

std::string BundledText() {
  std::ifstream in(BundledBlock());
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The bundled block with `from` replaced by `to`, parsed as if it were the
// file "blocks/bad.toml" in the samples folder (so frame_spec resolves).
std::string ErrorOf(const std::string& from, const std::string& to) {
  std::string text = BundledText();
  const std::size_t at = text.find(from);
  if (at == std::string::npos) return "(test error: '" + from + "' not in the bundled block)";
  text.replace(at, from.size(), to);
  try {
    ParseBlockSpec(text, BlocksDir() + "/bad.toml");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(BlockSpec, BundledBlockReadsWithEveryKey) {
  ASSERT_TRUE(IsBlockSpecFile(BundledBlock()));
  EXPECT_FALSE(IsBlockSpecFile(std::string(PLATEMETER_SOURCE_DIR) + "/samples/specs/hasselblad-passpoints.toml"));
  const BlockSpec spec = ReadBlockSpec(BundledBlock());
  EXPECT_EQ(spec.name, "hasselblad-block");
  EXPECT_EQ(spec.seed, 14u);
  EXPECT_EQ(std::filesystem::path(spec.frame_spec_path).filename(), "hasselblad-80-frame.toml");
  EXPECT_EQ(spec.frame_spec.camera, "hasselblad-80");
  EXPECT_EQ(spec.frame_spec.passpoints.shape, "ring");
  EXPECT_DOUBLE_EQ(spec.geometry.camera.c_mm, 80.3);
  EXPECT_DOUBLE_EQ(spec.geometry.camera.xp_mm, 0.012);
  EXPECT_DOUBLE_EQ(spec.geometry.camera.k2_per_mm4, -4.0e-10);
  EXPECT_DOUBLE_EQ(spec.geometry.camera.k3_per_mm6, 0.0);
  EXPECT_DOUBLE_EQ(spec.geometry.altitude_m, 108.5e3);
  EXPECT_EQ(spec.geometry.revolutions, (std::vector<int>{1, 2, 3}));
  EXPECT_DOUBLE_EQ(spec.geometry.convergence_deg, 80.0);
  EXPECT_TRUE(spec.geometry.rolls_continue_across_orbits);
  EXPECT_EQ(spec.geometry.passpoints, 60);
  EXPECT_DOUBLE_EQ(spec.geometry.relief_m, 300.0);
  EXPECT_DOUBLE_EQ(spec.geometry.format_margin_mm, 2.0);
  EXPECT_DOUBLE_EQ(spec.min_separation_mm, 1.5);
  EXPECT_EQ(spec.control.count, 4);
  EXPECT_DOUBLE_EQ(spec.control.sigma_m, 5.0);
  EXPECT_DOUBLE_EQ(spec.transfer.sigma_px, 3.0);
  EXPECT_DOUBLE_EQ(spec.frames.scanner_rotation_sigma_deg, 0.3);
  EXPECT_DOUBLE_EQ(spec.frames.film_affine_sigma_ppm, 20.0);
  EXPECT_DOUBLE_EQ(spec.geometry.approximations.station_sigma_m, 1000.0);
  EXPECT_EQ(spec.bundle.free, (std::vector<std::string>{"c", "xp", "yp", "k1", "k2", "p1", "p2"}));
  EXPECT_EQ(spec.bundle.measured_dir, "measured");
}

TEST(BlockSpec, MistakesNameTheFileTheLineAndTheKey) {
  const std::string file = BlocksDir() + "/bad.toml: line ";
  struct Case {
    std::string from, to, expected;
  };
  const std::vector<Case> cases = {
      {"convergence_deg = 80.0", "convergence_deg = 200.0", "orbits: key 'convergence_deg' = 200 must lie in 1..170"},
      {"relief_m = 300.0", "relif_m = 300.0", "points: unknown key 'relif_m'"},
      {"kappa_sequence = \"continuous\"", "kappa_sequence = \"sometimes\"",
       "orbits: key 'kappa_sequence' = 'sometimes' must be \"continuous\" or \"per-orbit\""},
      {"free = [\"c\",", "free = [\"f\",", "bundle: key 'free': 'f' is not one of c, xp, yp"},
      {"frame_spec = \"hasselblad-80-frame.toml\"", "frame_spec = \"nowhere.toml\"",
       "block: key 'frame_spec' = 'nowhere.toml': no such file"},
      {"c_mm = 80.3\n", "", "camera: missing required key 'c_mm'"},
      {"sigma_px = 3.0", "sigma_px = \"3\"", "transfer: key 'sigma_px' must be a number"},
      {"count = 4\n", "count = 61\n", "control: key 'count' = 61 must lie in 0..60"},
      {"revolutions = [1, 2, 3]", "revolutions = [1, 1, 3]", "orbits: key 'revolutions' has a value twice"},
      {"measured_dir = \"measured\"", "measured_dir = \"/tmp/x\"", "bundle: key 'measured_dir' must be a relative"},
      {"seed = 14", "seed = -1", "block: key 'seed' must be a non-negative integer"},
  };
  for (const Case& c : cases) {
    const std::string error = ErrorOf(c.from, c.to);
    EXPECT_THAT(error, HasSubstr(file)) << c.to;
    EXPECT_THAT(error, HasSubstr(c.expected)) << c.to;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  }
  // Whole tables.
  EXPECT_THAT(ErrorOf("[block]", "[blok]"), HasSubstr("unknown key 'blok' (the tables: block, camera"));
  EXPECT_THAT(ErrorOf("[camera]", "[kamera]"), HasSubstr("unknown key 'kamera'"));
  try {
    ParseBlockSpec("[camera]\nc_mm = 80.0\n", "only-camera.toml");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("only-camera.toml: missing table [block]"));
  }
  // A syntax error names the line.
  EXPECT_THAT(ErrorOf("seed = 14", "seed = = 14"), HasSubstr(BlocksDir() + "/bad.toml: line "));
}

TEST(BlockSpec, AFrameSpecProblemNamesTheFrameSpec) {
  platemeter::testing::TempDir dir;
  std::string text = BundledText();
  const std::string from = "frame_spec = \"hasselblad-80-frame.toml\"";
  text.replace(text.find(from), from.size(), "frame_spec = \"frame.toml\"");
  std::ofstream(dir.file("block.toml")) << text;
  std::ofstream(dir.file("frame.toml")) << "name = \"f\"\ncamera = \"hasselblad-70\"\n";
  const BlockSpec spec = ReadBlockSpec(dir.file("block.toml"));
  try {
    LayOutBlock(spec, DefinitionRegistry());
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr(dir.file("frame.toml") + ": unknown camera 'hasselblad-70'"));
  }
  std::ofstream(dir.file("frame.toml")) << "name = \"f\"\ncamera = \"hasselblad-80\"\n[noise]\nblur_um = 3\n";
  try {
    ReadBlockSpec(dir.file("block.toml"));
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr(dir.file("frame.toml") + ": line 4: noise: unknown key 'blur_um'"));
  }
}

class BlockLayoutTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    spec_ = new BlockSpec(ReadBlockSpec(BundledBlock()));
    layout_ = new BlockLayout(LayOutBlock(*spec_, DefinitionRegistry()));
  }
  static void TearDownTestSuite() {
    delete layout_;
    delete spec_;
  }
  static BlockSpec* spec_;
  static BlockLayout* layout_;
};
BlockSpec* BlockLayoutTest::spec_ = nullptr;
BlockLayout* BlockLayoutTest::layout_ = nullptr;

TEST_F(BlockLayoutTest, FramesSeeSeparatedPointsWithControlAndApproximations) {
  const BlockLayout& layout = *layout_;
  EXPECT_EQ(layout.camera_definition, "hasselblad-80");
  EXPECT_DOUBLE_EQ(layout.camera.format_width_mm, 55.0);
  ASSERT_EQ(layout.frames.size(), 9u);
  EXPECT_EQ(layout.points.size() + layout.dropped.size(), 60u);
  EXPECT_GE(layout.points.size(), 50u);
  ASSERT_EQ(layout.ground_points.size(), layout.points.size());
  ASSERT_EQ(layout.approximations.size(), 9u);
  for (std::size_t i = 0; i < layout.points.size(); ++i) {
    const GroundPoint& g = layout.ground_points[i];
    EXPECT_EQ(g.id, layout.points[i].id);
    if (layout.control[i]) {
      EXPECT_LT(i, 4u);
      for (int k = 0; k < 3; ++k) {
        ASSERT_TRUE(g.sigma_m[k].has_value());
        EXPECT_DOUBLE_EQ(*g.sigma_m[k], 5.0);
      }
      EXPECT_LT((g.position_m - layout.points[i].position_m).norm(), 5.0 * 5.0);  // truth perturbed by 5 m
    } else {
      EXPECT_FALSE(g.sigma_m[0] || g.sigma_m[1] || g.sigma_m[2]);
    }
  }
  EXPECT_EQ(std::count(layout.control.begin(), layout.control.end(), true), 4);
  std::set<double> rolls;
  for (std::size_t f = 0; f < layout.frames.size(); ++f) {
    const BlockFrame& frame = layout.frames[f];
    EXPECT_EQ(frame.points.size(), layout.points.size()) << frame.station.id;  // min_frames 0: every frame
    rolls.insert(frame.station.roll_deg);
    for (std::size_t i = 0; i < frame.plate_mm.size(); ++i) {
      EXPECT_LE(std::abs(frame.plate_mm[i].x()), 27.5 - 2.0);
      EXPECT_LE(std::abs(frame.plate_mm[i].y()), 27.5 - 2.0);
      for (std::size_t j = 0; j < i; ++j) EXPECT_GE((frame.plate_mm[i] - frame.plate_mm[j]).norm(), 1.5);
    }
    // Approximations: near the truth, not at it.
    const FrameSetup& a = layout.approximations[f];
    ASSERT_TRUE(a.position_m && a.angles);
    const double off_m = (*a.position_m - frame.station.position_m).norm();
    EXPECT_GT(off_m, 1.0);
    EXPECT_LT(off_m, 6000.0);
  }
  EXPECT_EQ(rolls.size(), 4u);  // kappa steps of 90 deg: 0, 90, 180, -90
}

TEST_F(BlockLayoutTest, TheLensEntersOnceAndTheChainAddsNoOther) {
  const BlockLayout& layout = *layout_;
  const BundleCameraTruth& camera = layout.camera;
  const auto values = camera.Values();
  BundleCameraTruth pinhole = camera;
  pinhole.k1_per_mm2 = pinhole.k2_per_mm4 = pinhole.p1_per_mm = pinhole.p2_per_mm = 0.0;
  const auto pinhole_values = pinhole.Values();
  double largest_distortion_um = 0.0;
  for (std::size_t f : {std::size_t{0}, std::size_t{4}, std::size_t{8}}) {
    const BlockFrame& frame = layout.frames[f];
    double rotation[9];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rotation[3 * r + c] = frame.station.image_from_object(r, c);
    }
    for (std::size_t i = 0; i < frame.points.size(); ++i) {
      const Eigen::Vector3d direction = layout.points[frame.points[i]].position_m - frame.station.position_m;
      double with_lens[2], without_lens[2];
      ASSERT_TRUE(CollinearityResidualT<BrownAffine>(values.data(), values.data() + 3, rotation, direction.data(),
                                                     frame.plate_mm[i].x(), frame.plate_mm[i].y(), with_lens));
      ASSERT_TRUE(CollinearityResidualT<BrownAffine>(pinhole_values.data(), pinhole_values.data() + 3, rotation,
                                                     direction.data(), frame.plate_mm[i].x(), frame.plate_mm[i].y(),
                                                     without_lens));
      // Seed 000 eq. 1 with the true camera holds exactly; without its distortion it does not.
      EXPECT_LT(std::hypot(with_lens[0], with_lens[1]), 1e-9);
      largest_distortion_um = std::max(largest_distortion_um, 1e3 * std::hypot(without_lens[0], without_lens[1]));
    }

    // The frame's plate: its passpoints at exactly those positions, and the
    // chain (thermal, emulsion, film, scanner) maps them to pixels and back
    // with no lens: the truth file's x_mm, y_mm are the projected positions.
    const SimulationSpec frame_spec = FrameSimulationSpec(*spec_, layout, f);
    EXPECT_EQ(frame_spec.name, frame.station.id);
    EXPECT_EQ(frame_spec.passpoints.count, 0);
    EXPECT_DOUBLE_EQ(*frame_spec.emulsion.principal_distance_mm, camera.c_mm);
    const SimulatedPlate plate = BuildSimulatedPlate(frame_spec, DefinitionRegistry());
    std::size_t passpoints = 0;
    for (const MeasuredPoint& t : plate.truth) {
      if (t.kind != PointKind::kPasspoint) continue;
      const std::size_t i = passpoints++;
      ASSERT_LT(i, frame.points.size());
      EXPECT_EQ(t.id, layout.points[frame.points[i]].id);
      EXPECT_EQ(*t.x_mm, frame.plate_mm[i].x());
      EXPECT_EQ(*t.y_mm, frame.plate_mm[i].y());
      const PlatePoint back = plate.chain.PlateFromPixel({*t.x_px, *t.y_px});
      EXPECT_NEAR(back.x_mm, frame.plate_mm[i].x(), 1e-9);
      EXPECT_NEAR(back.y_mm, frame.plate_mm[i].y(), 1e-9);
      EXPECT_TRUE(t.flags.empty()) << t.id;  // on the scan
    }
    EXPECT_EQ(passpoints, frame.points.size());
    EXPECT_DOUBLE_EQ(plate.chain.scanner.rotation_deg, frame.scanner_rotation_deg);
  }
  // The true lens moves points by tens of micrometres (~80 um radial at the corner).
  EXPECT_GT(largest_distortion_um, 40.0);
  EXPECT_LT(largest_distortion_um, 120.0);
}

TEST_F(BlockLayoutTest, PasspointListsAreTheTruthPerturbedByTheTransferSigma) {
  const BlockLayout& layout = *layout_;
  const SimulatedPlate plate = BuildSimulatedPlate(FrameSimulationSpec(*spec_, layout, 1), DefinitionRegistry());
  const std::string csv = PasspointListCsv(*spec_, layout.frames[1], plate);
  std::stringstream lines(csv);
  std::string line;
  std::vector<std::string> rows;
  while (std::getline(lines, line)) {
    if (!line.empty() && line[0] != '#') rows.push_back(line);
  }
  ASSERT_EQ(rows.size(), layout.frames[1].points.size() + 1);
  EXPECT_EQ(rows[0], "id,x_px,y_px");
  double sum_squares = 0.0;
  int n = 0;
  std::size_t row = 1;
  for (const MeasuredPoint& t : plate.truth) {
    if (t.kind != PointKind::kPasspoint) continue;
    std::stringstream fields(rows[row++]);
    std::string id, x, y;
    std::getline(fields, id, ',');
    std::getline(fields, x, ',');
    std::getline(fields, y, ',');
    EXPECT_EQ(id, t.id);
    const double dx = std::stod(x) - *t.x_px, dy = std::stod(y) - *t.y_px;
    EXPECT_LT(std::hypot(dx, dy), 5.0 * spec_->transfer.sigma_px);
    sum_squares += dx * dx + dy * dy;
    n += 2;
  }
  const double rms_px = std::sqrt(sum_squares / n);
  EXPECT_GT(rms_px, 0.7 * spec_->transfer.sigma_px);
  EXPECT_LT(rms_px, 1.3 * spec_->transfer.sigma_px);
}

}  // namespace
}  // namespace platemeter::sim
