// The built-in SN-004 definitions against seed 004 as printed: every cross of
// Tables A.1 and A.3, every fiducial of Table A.2 and every lens constant of
// Tables A.4 and A.5, read from the seed text by the parser in seed_text.h.
#include <gtest/gtest.h>

#include "grids/seed_text.h"
#include "platemeter/grids/registry.h"

namespace platemeter {
namespace {

using testing::SeedCrossTable;
using testing::SeedFiducialTable;
using testing::SeedLensTable;

void ExpectGridMatchesSeed(const MasterGrid& grid, const std::map<std::string, testing::SeedPoint>& seed) {
  // Both directions: a point missing on either side fails.
  EXPECT_EQ(grid.points.size(), seed.size());
  for (const auto& [id, point] : seed) {
    const GridPoint* built_in = grid.Find(id);
    ASSERT_NE(built_in, nullptr) << grid.name << " lacks " << id;
    EXPECT_EQ(built_in->x_mm, point.x_mm) << grid.name << " " << id;
    EXPECT_EQ(built_in->y_mm, point.y_mm) << grid.name << " " << id;
  }
  for (const GridPoint& point : grid.points) EXPECT_TRUE(seed.count(point.id)) << "not in the seed: " << point.id;
}

TEST(SeedTables, ParserFindsEveryPointOfTheSeed) {
  EXPECT_EQ(SeedCrossTable("A.1").size(), 121u);
  EXPECT_EQ(SeedCrossTable("A.3").size(), 25u);
  EXPECT_EQ(SeedFiducialTable().size(), 8u);
  EXPECT_EQ(SeedLensTable("TABLE A.4").size(), 9u);
  EXPECT_EQ(SeedLensTable("TABLE A.5").size(), 9u);
}

TEST(SeedTables, IkogonBIsTableA1) {
  const DefinitionRegistry registry;
  const MasterGrid& grid = registry.Grid("ikogon-b");
  EXPECT_EQ(grid.columns, 11);
  EXPECT_EQ(grid.rows, 11);
  ExpectGridMatchesSeed(grid, SeedCrossTable("A.1"));
}

TEST(SeedTables, IkotarBIsTableA3) {
  const DefinitionRegistry registry;
  const MasterGrid& grid = registry.Grid("ikotar-b");
  EXPECT_EQ(grid.columns, 5);
  EXPECT_EQ(grid.rows, 5);
  ExpectGridMatchesSeed(grid, SeedCrossTable("A.3"));
}

TEST(SeedTables, TerrainFiducialsAreTableA2) {
  const DefinitionRegistry registry;
  const FiducialSet& set = registry.Fiducials("sn004-terrain-fiducials");
  const auto seed = SeedFiducialTable();
  EXPECT_EQ(set.marks.size(), seed.size());
  for (const auto& [id, point] : seed) {
    const FiducialMark* mark = set.Find(id);
    ASSERT_NE(mark, nullptr) << "missing fiducial " << id;
    EXPECT_EQ(mark->x_mm, point.x_mm) << id;
    EXPECT_EQ(mark->y_mm, point.y_mm) << id;
  }
}

TEST(SeedTables, SpotValuesTypedByHand) {
  const DefinitionRegistry registry;
  const MasterGrid& ikogon = registry.Grid("ikogon-b");
  EXPECT_EQ(ikogon.Find("X1Y1")->x_mm, -50.0014);
  EXPECT_EQ(ikogon.Find("X1Y1")->y_mm, -50.0019);
  EXPECT_EQ(ikogon.Find("X5Y7")->x_mm, -9.9990);
  EXPECT_EQ(ikogon.Find("X5Y7")->y_mm, 10.0000);
  EXPECT_EQ(ikogon.Find("X11Y11")->x_mm, 50.0029);
  EXPECT_EQ(ikogon.Find("X11Y11")->y_mm, 49.9969);
  EXPECT_EQ(ikogon.Find("X10Y3")->x_mm, 40.0019);
  EXPECT_EQ(ikogon.Find("X10Y3")->y_mm, -30.0030);
  const MasterGrid& ikotar = registry.Grid("ikotar-b");
  EXPECT_EQ(ikotar.Find("X2Y4")->x_mm, -5.0008);
  EXPECT_EQ(ikotar.Find("X2Y4")->y_mm, 5.0005);
  EXPECT_EQ(ikotar.Find("X1Y2")->y_mm, -5.0011);
  EXPECT_EQ(ikotar.Find("X5Y1")->x_mm, 9.9996);
  const FiducialSet& fiducials = registry.Fiducials("sn004-terrain-fiducials");
  EXPECT_EQ(fiducials.Find("A'")->x_mm, -60.555);
  EXPECT_EQ(fiducials.Find("A'")->y_mm, 30.796);
  EXPECT_EQ(fiducials.Find("D")->x_mm, -0.011);
  EXPECT_EQ(fiducials.Find("C'")->y_mm, -60.566);
}

// Table symbol -> LensCalibration field or coefficient key.
double LensValue(const LensCalibration& lens, const std::string& symbol, bool sigma) {
  static const std::map<std::string, std::string> keys = {
      {"FL", "principal_distance_mm"}, {"X_p", "principal_point_x_mm"}, {"Y_p", "principal_point_y_mm"},
      {"K_1", "K1_per_mm2"},           {"K_2", "K2_per_mm4"},           {"K_3", "K3_per_mm6"},
      {"J_1", "J1_per_mm"},            {"J_2", "J2_per_mm3"},           {"\\theta_0", "theta0_rad"}};
  const std::string& key = keys.at(symbol);
  if (sigma) return lens.sigmas.at(key);
  if (key == "principal_distance_mm") return lens.principal_distance_mm;
  if (key == "principal_point_x_mm") return lens.principal_point_x_mm;
  if (key == "principal_point_y_mm") return lens.principal_point_y_mm;
  return lens.coefficients.at(key);
}

void ExpectLensMatchesSeed(const CameraDefinition& camera, const std::string& caption) {
  ASSERT_TRUE(camera.lens.has_value());
  EXPECT_EQ(camera.lens->model, "smac-radial-decentering");
  const auto seed = SeedLensTable(caption);
  ASSERT_EQ(seed.size(), 9u);
  EXPECT_EQ(camera.lens->coefficients.size(), 6u);
  for (const auto& [symbol, value_sd] : seed) {
    EXPECT_EQ(LensValue(*camera.lens, symbol, false), value_sd.first) << camera.name << " " << symbol;
    EXPECT_EQ(LensValue(*camera.lens, symbol, true), value_sd.second) << camera.name << " S.D. " << symbol;
  }
}

TEST(SeedTables, TerrainLensIsTableA4) {
  const DefinitionRegistry registry;
  const CameraDefinition& camera = registry.Camera("sn004-terrain");
  ExpectLensMatchesSeed(camera, "TABLE A.4");
  // By hand: "K_1 = -0.1278842 ^{-05}" is -0.1278842e-05 per mm^2.
  EXPECT_EQ(camera.lens->coefficients.at("K1_per_mm2"), -0.1278842e-05);
  EXPECT_EQ(camera.lens->principal_distance_mm, 75.8069);
  EXPECT_EQ(camera.format_width_mm, 4.5 * 25.4);
  EXPECT_EQ(camera.grid, "ikogon-b");
  EXPECT_EQ(camera.fiducial_set, "sn004-terrain-fiducials");
}

TEST(SeedTables, StellarLensIsTableA5) {
  const DefinitionRegistry registry;
  const CameraDefinition& camera = registry.Camera("sn004-stellar");
  ExpectLensMatchesSeed(camera, "TABLE A.5");
  EXPECT_EQ(camera.lens->coefficients.at("theta0_rad"), 3.870122);
  EXPECT_EQ(camera.grid, "ikotar-b");
  // The chosen format must hold the whole Ikotar B grid.
  for (const GridPoint& point : registry.Grid("ikotar-b").points) {
    EXPECT_LT(std::abs(point.x_mm), camera.format_width_mm / 2);
    EXPECT_LT(std::abs(point.y_mm), camera.format_height_mm / 2);
  }
}

}  // namespace
}  // namespace platemeter
