// Catalog stars on a simulated plate: stars below the horizon or outside the
// format give no image; the truth file carries star_id, trail, dot and
// mid_time_utc and round-trips; random-star mode is unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>

#include <erfa.h>

#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "platemeter/samples/star_field.h"
#include "support/test_support.h"
#include "platemeter/core/angles.h"

namespace platemeter::sim {
namespace {


TEST(StarFieldPlate, BelowTheHorizonOrOutsideTheFormatGivesNoImage) {
  StarFieldOptions o;
  o.place.site = {39.03 * kRadPerDeg, -76.93 * kRadPerDeg, 50.0};
  o.start_utc = calib::ParseUtcIso8601("1972-05-12T06:00:00Z");
  o.duty_cycle = false;
  o.single_exposure_s = 10.0;
  double u1, u2, t1, t2, tai1, tai2;
  ASSERT_EQ(eraDtf2d("UTC", 1972, 5, 12, 6, 0, 5.0, &u1, &u2), 0);
  eraUtctai(u1, u2, &tai1, &tai2);
  eraTaitt(tai1, tai2, &t1, &t2);
  const double lst = eraGmst06(u1, u2, t1, t2) + o.place.site.longitude_rad;
  auto star = [&](int id, double hour_angle_deg, double dec_deg) {
    calib::CatalogStar s;
    s.id = id;
    s.ra_rad = eraAnp(lst - hour_angle_deg * kRadPerDeg);
    s.dec_rad = dec_deg * kRadPerDeg;
    s.v_mag = 3.0;
    return s;
  };
  // 1: near the zenith. 2: dec -80 never rises at 39 N. 3: 75 deg west of the
  // meridian at dec 39: z ~ 55 deg, beyond the 45 deg corner of a 114 mm
  // format at c = 80 mm. 4: 70 deg south of the zenith (dec -31, H 0): up, but
  // outside.
  const std::vector<calib::CatalogStar> stars = {star(1, 2.0, 40.0), star(2, 0.0, -80.0), star(3, 75.0, 39.0),
                                                 star(4, 0.0, -31.0)};
  CameraDefinition camera;
  camera.name = "pinhole";
  camera.format_width_mm = 114.0;
  camera.format_height_mm = 114.0;
  camera.nominal_principal_distance_mm = 80.0;
  const StarFieldResult r = ComputeStarImages(o, stars, PlateLens(camera), 114.0, 114.0);
  ASSERT_EQ(r.images.size(), 1u);
  EXPECT_EQ(r.images[0].star_id, "KS1");
  EXPECT_EQ(r.skipped_below_horizon, 1);
  EXPECT_EQ(r.skipped_outside, 2);
  // A single 10 s exposure: the segment spans 10 s of diurnal motion,
  // ~150" cos(dec) on the sky, i.e. ~0.045 mm at c = 80 mm.
  const StarImage& image = r.images[0];
  const double length_mm = std::hypot(image.close_mm.x_mm - image.open_mm.x_mm, image.close_mm.y_mm - image.open_mm.y_mm);
  const double expected_mm = 80.0 * 10.0 * 15.0411 / 206264.806 * std::cos(40.0 * kRadPerDeg);
  EXPECT_NEAR(length_mm, expected_mm, 0.02 * expected_mm);
}

bool HaveCatalog() { return std::filesystem::exists(calib::DefaultStarCatalogPath()); }

TEST(StarFieldPlate, TruthFileCarriesTrailsAndRoundTrips) {
  if (!HaveCatalog()) GTEST_SKIP() << "kstars-data's stars.dat is missing (scripts/setup installs it)";
  const std::string text = R"(
name = "trails"
camera = "orbigon"
[output]
pixel_size_um = 200
[stars]
fwhm_um = 30
reference_peak_dn = 3000
[star_field]
latitude_deg = 39.03
longitude_deg = -76.93
height_m = 50
start_utc = "1972-05-12T05:30:00Z"
magnitude_limit = 2.5
)";
  const SimulationSpec spec = ParseSimulationSpec(text, "trails.toml");
  ASSERT_TRUE(spec.star_field.enabled);
  SimulatedPlate plate = BuildSimulatedPlate(spec, DefinitionRegistry());
  std::set<std::string> ids, stars;
  long dots = 0, dashes = 0;
  for (size_t i = 0; i < plate.truth.size(); ++i) {
    const MeasuredPoint& t = plate.truth[i];
    EXPECT_TRUE(ids.insert(t.id).second) << "duplicate id " << t.id;
    if (t.kind != PointKind::kTrailDot && t.kind != PointKind::kTrailDash) continue;
    (t.kind == PointKind::kTrailDot ? dots : dashes)++;
    stars.insert(t.star_id);
    EXPECT_FALSE(t.star_id.empty());
    EXPECT_FALSE(t.trail.empty());
    EXPECT_TRUE(t.dot.has_value());
    EXPECT_EQ(t.mid_time_utc.substr(0, 11), "1972-05-12T");
    const std::string expected_id =
        t.star_id + "-" + t.trail + (t.kind == PointKind::kTrailDot ? "-D" : "-L") + std::to_string(*t.dot);
    EXPECT_EQ(t.id, expected_id);
    // Inside the format, and the truth pixel is the chain's image of the truth plate point.
    EXPECT_LE(std::abs(*t.x_mm), 57.0);
    EXPECT_LE(std::abs(*t.y_mm), 57.0);
    const PixelPoint px = plate.chain.PixelFromPlate({*t.x_mm, *t.y_mm});
    EXPECT_NEAR(*t.x_px, px.x_px, 1e-9);
    EXPECT_NEAR(*t.y_px, px.y_px, 1e-9);
    // The mark: a segment whose centre is within 0.1 um (5e-4 px) of the truth.
    const SceneMark& m = plate.scene.marks[static_cast<size_t>(plate.truth_mark[i])];
    EXPECT_EQ(m.shape, MarkShapeKind::kSegment);
    EXPECT_EQ(m.kind, t.kind == PointKind::kTrailDot ? MarkKind::kTrailDot : MarkKind::kTrailDash);
    EXPECT_NEAR(m.centre_px.x_px, *t.x_px, 5e-4);
    EXPECT_NEAR(m.centre_px.y_px, *t.y_px, 5e-4);
  }
  EXPECT_GT(stars.size(), 3u);  // V <= 2.5 within 45 deg of the zenith over two hours
  EXPECT_GT(dots, 50);
  EXPECT_GT(dashes, 10);

  testing::TempDir dir;
  const SimulateOutputs out = WriteSimulatedPlate(std::move(plate), dir.path().string());
  const MeasurementFile truth = ReadMeasurementFile(out.truth_path);
  long read_dots = 0, with_crb = 0;
  for (const MeasuredPoint& t : truth.points) {
    if (t.kind != PointKind::kTrailDot) continue;
    ++read_dots;
    EXPECT_FALSE(t.star_id.empty());
    EXPECT_EQ(t.trail.substr(0, 1), "T");
    ASSERT_TRUE(t.dot.has_value());
    EXPECT_GE(*t.dot, 1);
    EXPECT_LE(*t.dot, 25);
    EXPECT_EQ(t.mid_time_utc.size(), std::string("1972-05-12T05:31:00.300Z").size());
    if (t.crb_x_px && *t.crb_x_px > 0) ++with_crb;
  }
  EXPECT_EQ(read_dots, dots);
  EXPECT_EQ(with_crb, dots);
}

TEST(StarFieldPlate, RandomStarModeIsUnchanged) {
  const SimulatedPlate plate = BuildSimulatedPlate(
      ParseSimulationSpec("name = \"r\"\ncamera = \"orbigon\"\n[output]\npixel_size_um = 200\n[stars]\ncount = 7\n", "r.toml"),
      DefinitionRegistry());
  int stars = 0;
  for (size_t i = 0; i < plate.truth.size(); ++i) {
    const MeasuredPoint& t = plate.truth[i];
    EXPECT_NE(t.kind, PointKind::kTrailDot);
    EXPECT_NE(t.kind, PointKind::kTrailDash);
    if (t.kind != PointKind::kStar) continue;
    ++stars;
    const SceneMark& m = plate.scene.marks[static_cast<size_t>(plate.truth_mark[i])];
    EXPECT_EQ(m.kind, MarkKind::kStar);
    EXPECT_EQ(m.shape, MarkShapeKind::kPsf);
    EXPECT_TRUE(t.star_id.empty());
    EXPECT_LE(std::abs(*t.x_mm), 57.0);
  }
  EXPECT_EQ(stars, 7);
  EXPECT_TRUE(plate.star_field_json.empty());
}

TEST(StarFieldPlate, SpecErrorsNameTheKey) {
  EXPECT_THROW(ParseSimulationSpec("name = \"x\"\ncamera = \"orbigon\"\n[star_field]\nlatitude_deg = 39\n", "x.toml"),
               Error);  // start_utc is required
  try {
    ParseSimulationSpec("name = \"x\"\ncamera = \"orbigon\"\n[star_field]\nstart_utc = \"1972-05-12T05:30:00Z\"\n"
                        "leading_dashes = [2, 6]\n",
                        "x.toml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("leading_dashes"), std::string::npos) << e.what();
  }
  SimulationSpec bad = ParseSimulationSpec(
      "name = \"x\"\ncamera = \"orbigon\"\n[star_field]\nstart_utc = \"1972-13-12T05:30:00Z\"\n", "x.toml");
  try {
    BuildSimulatedPlate(bad, DefinitionRegistry());
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("start_utc"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace platemeter::sim
