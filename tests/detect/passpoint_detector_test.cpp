// Passpoint detection on simulator plates (the bundled Hasselblad spec: 40
// random dark rings and PUG-1 over terrain, four bright format corners):
// automatic mode finds every ring and nothing else, at the Cramer-Rao bound;
// bright rings among dust disks of their own size; a dot variant among dust;
// list mode keeps the user's ids, reports an entry with no mark as missing,
// masked and ambiguous entries, and faint, thick and damaged rings as
// rejected with their reasons; bad list files fail with file and line.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/detect/passpoint_detector.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/measurement_file.h"
#include "platemeter/samples/simulate.h"
#include "platemeter/samples/spec.h"
#include "support/test_support.h"

namespace platemeter {
namespace {

using testing::TempDir;

std::string BundledSpec() {
  std::ifstream in(std::string(PLATEMETER_SOURCE_DIR) + "/samples/specs/hasselblad-passpoints.toml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The scan and its truth passpoints (with their Cramer-Rao bounds, from the truth file).
struct RenderedPasspoints {
  std::string image_path;
  double pixel_size_um = 0.0;
  std::vector<MeasuredPoint> truth;        // kind passpoint
  std::vector<MeasuredPoint> fiducials;    // the format corners
  std::vector<std::pair<PixelPoint, double>> dust;  // centre, radius in px
};

RenderedPasspoints RenderPasspoints(const std::string& toml, const TempDir& dir) {
  const DefinitionRegistry registry;
  const sim::SimulationSpec spec = sim::ParseSimulationSpec(toml, "test spec");
  sim::SimulatedPlate plate = sim::BuildSimulatedPlate(spec, registry);
  RenderedPasspoints r;
  r.pixel_size_um = plate.pixel_size_um;
  for (int k : plate.dust) {
    const sim::SceneMark& m = plate.scene.marks[static_cast<size_t>(k)];
    r.dust.push_back({m.centre_px, 0.5 * m.size_um / plate.pixel_size_um});
  }
  const sim::SimulateOutputs out = sim::WriteSimulatedPlate(std::move(plate), dir.path().string());
  r.image_path = out.image_path;
  for (const MeasuredPoint& p : ReadMeasurementFile(out.truth_path).points) {
    if (p.kind == PointKind::kPasspoint) r.truth.push_back(p);
    if (p.kind == PointKind::kFiducial) r.fiducials.push_back(p);
  }
  return r;
}

PasspointDetectorOptions RingOptions(double pixel_size_um) {
  PasspointDetectorOptions o;
  o.shape = MarkType::kRing;
  o.diameter_px = 250.0 / pixel_size_um;
  o.line_width_px = 50.0 / pixel_size_um;
  o.dark = true;
  return o;
}

// Every detection matched to the nearest truth passpoint (one to one), and the scatter against truth.
struct Comparison {
  int matched = 0, false_points = 0, duplicates = 0;
  double rms_error_px = 0, rms_crb_px = 0, rms_normalized = 0;  // per axis
  std::map<std::string, std::string> id_of_truth;                 // truth id -> detected id
};

Comparison Compare(const PasspointDetection& found, const std::vector<MeasuredPoint>& truth) {
  Comparison c;
  double e2 = 0, crb2 = 0, n2 = 0;
  for (const PasspointPoint& p : found.points) {
    if (p.point.status != PointStatus::kMeasured) continue;
    const MeasuredPoint* best = nullptr;
    double best_d = 2.0;  // px
    for (const MeasuredPoint& t : truth) {
      const double d = std::hypot(p.point.position_px.x_px - *t.x_px, p.point.position_px.y_px - *t.y_px);
      if (d < best_d) best_d = d, best = &t;
    }
    if (!best) {
      ++c.false_points;
      std::printf("false point %s at (%.2f, %.2f)\n", p.point.id.c_str(), p.point.position_px.x_px, p.point.position_px.y_px);
      continue;
    }
    if (c.id_of_truth.count(best->id)) {
      ++c.duplicates;
      continue;
    }
    c.id_of_truth[best->id] = p.point.id;
    ++c.matched;
    const double ex = p.point.position_px.x_px - *best->x_px, ey = p.point.position_px.y_px - *best->y_px;
    e2 += ex * ex + ey * ey;
    crb2 += *best->crb_x_px * *best->crb_x_px + *best->crb_y_px * *best->crb_y_px;
    n2 += ex * ex / (p.point.sigma_x_px * p.point.sigma_x_px) + ey * ey / (p.point.sigma_y_px * p.point.sigma_y_px);
  }
  if (c.matched > 0) {
    c.rms_error_px = std::sqrt(e2 / (2 * c.matched));
    c.rms_crb_px = std::sqrt(crb2 / (2 * c.matched));
    c.rms_normalized = std::sqrt(n2 / (2 * c.matched));
  }
  return c;
}

// The marks no dust disk reaches (mark_radius_px + 4 px of it) and how many of them were measured.
std::pair<int, int> CleanMarks(const RenderedPasspoints& r, const Comparison& c, double mark_radius_px) {
  int clean = 0, found = 0;
  for (const MeasuredPoint& t : r.truth) {
    bool touched = false;
    for (const auto& [centre, radius] : r.dust)
      touched = touched || std::hypot(centre.x_px - *t.x_px, centre.y_px - *t.y_px) < radius + mark_radius_px + 4.0;
    if (touched) continue;
    ++clean;
    found += c.id_of_truth.count(t.id) > 0;
  }
  return {clean, found};
}

// The bundled plate, rendered once for the tests that use it as it is.
class BundledPlate : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    plate_ = new RenderedPasspoints(RenderPasspoints(BundledSpec(), *dir_));
  }
  static void TearDownTestSuite() {
    delete plate_;
    delete dir_;
    plate_ = nullptr, dir_ = nullptr;
  }
  static TempDir* dir_;
  static RenderedPasspoints* plate_;
};
TempDir* BundledPlate::dir_ = nullptr;
RenderedPasspoints* BundledPlate::plate_ = nullptr;

TEST_F(BundledPlate, AutomaticModeFindsEveryRingAndNothingElse) {
  const RenderedPasspoints& r = *plate_;
  ASSERT_EQ(r.truth.size(), 41u);
  const Image image = Image::Open(r.image_path);
  PasspointDetectorOptions options = RingOptions(r.pixel_size_um);
  options.tile_px = 1024;  // several tiles, so marks near tile borders are exercised
  const PasspointDetection found = DetectPasspoints(image, options);
  std::printf("%s\n", found.summary.c_str());
  const Comparison c = Compare(found, r.truth);
  std::printf("matched %d of %zu, RMS error %.4f px, RMS CRB %.4f px, RMS/CRB %.3f, RMS error/sigma %.3f\n", c.matched,
              r.truth.size(), c.rms_error_px, c.rms_crb_px, c.rms_error_px / c.rms_crb_px, c.rms_normalized);
  EXPECT_EQ(found.tiles, 9);
  EXPECT_EQ(found.measured, 41);
  EXPECT_EQ(found.rejected, 0);
  EXPECT_EQ(c.matched, 41);
  EXPECT_EQ(c.false_points, 0);  // the four format corners, terrain and noise are not passpoints
  EXPECT_EQ(c.duplicates, 0);
  // 82 coordinates: the RMS of a correct estimator at the bound is within about +-16 % (2 sigma) of it.
  EXPECT_LE(c.rms_error_px / c.rms_crb_px, 1.3);
  EXPECT_GT(c.rms_normalized, 0.7);  // formal sigmas neither too small nor too large
  EXPECT_LT(c.rms_normalized, 1.3);
  // Ids P1.. in row-major order of position.
  for (size_t i = 0; i < found.points.size(); ++i) {
    EXPECT_EQ(found.points[i].point.id, "P" + std::to_string(i + 1));
    if (i > 0) {
      EXPECT_GE(found.points[i].point.position_px.y_px, found.points[i - 1].point.position_px.y_px);
    }
  }
  // The same rings seen as bright marks are not there; as dots they are the wrong shape.
  PasspointDetectorOptions bright = options;
  bright.dark = false;
  const PasspointDetection as_bright = DetectPasspoints(image, bright);
  std::printf("as bright: %s\n", as_bright.summary.c_str());
  EXPECT_EQ(as_bright.points.size(), 0u);
  PasspointDetectorOptions dots = options;
  dots.shape = MarkType::kDot;
  const PasspointDetection as_dots = DetectPasspoints(image, dots);
  std::printf("as dots: %s\n", as_dots.summary.c_str());
  EXPECT_EQ(as_dots.points.size(), 0u);
}

// List mode: the user's ids; an entry with no mark nearby, or off the scan, is
// missing; a masked mark is no passpoint; two marks in the window are ambiguous.
TEST_F(BundledPlate, ListModeKeepsTheUsersIdsAndNeverFabricates) {
  const RenderedPasspoints& r = *plate_;
  const Image image = Image::Open(r.image_path);
  PasspointDetectorOptions options = RingOptions(r.pixel_size_um);  // search radius: 2 diameters = 25 px
  // Operator clicks: up to 10 px off, every other passpoint, ids of the user's own.
  std::vector<ApproximatePasspoint> list;
  std::map<std::string, const MeasuredPoint*> truth_of;
  for (size_t i = 0; i < r.truth.size(); i += 2) {
    const double dx = 10.0 * std::cos(1.7 * i), dy = 10.0 * std::sin(1.7 * i);
    list.push_back({"user-" + r.truth[i].id, {*r.truth[i].x_px + dx, *r.truth[i].y_px + dy}});
    truth_of[list.back().id] = &r.truth[i];
  }
  const size_t listed = list.size();
  // Nothing there: 3 mm (the clearance) from every passpoint; one beyond the scan's edge.
  PixelPoint empty{*r.truth[3].x_px, *r.truth[3].y_px};
  for (double step = 0;; step += 10.0) {
    empty = {*r.truth[3].x_px + step, *r.truth[3].y_px + 0.5 * step};
    double nearest = 1e300;
    for (const MeasuredPoint& t : r.truth) nearest = std::min(nearest, std::hypot(*t.x_px - empty.x_px, *t.y_px - empty.y_px));
    if (nearest > 60.0) break;
  }
  list.push_back({"nothing-here", empty});
  list.push_back({"off-scan", {-40.0, 100.0}});
  // A passpoint under a mask (as if a cross were there), the mask a segment passing 3 px from its centre.
  const MeasuredPoint& hidden = r.truth[1];
  list.push_back({"masked", {*hidden.x_px + 2.0, *hidden.y_px}});
  options.mask.push_back({{*hidden.x_px - 50, *hidden.y_px + 3}, {*hidden.x_px + 50, *hidden.y_px + 3}, 4.0});
  const PasspointDetection found = DetectPasspoints(image, options, &list);
  std::printf("%s\n", found.summary.c_str());
  ASSERT_EQ(found.points.size(), list.size());
  EXPECT_TRUE(found.from_list);
  double n2 = 0;
  for (size_t i = 0; i < listed; ++i) {
    const PasspointPoint& p = found.points[i];
    EXPECT_EQ(p.point.id, list[i].id);
    EXPECT_EQ(p.point.kind, PointKind::kPasspoint);
    ASSERT_EQ(p.point.status, PointStatus::kMeasured) << p.point.id << " " << p.point.reason;
    const MeasuredPoint& t = *truth_of[p.point.id];
    const double ex = p.point.position_px.x_px - *t.x_px, ey = p.point.position_px.y_px - *t.y_px;
    EXPECT_LT(std::hypot(ex, ey), 0.1) << p.point.id;
    n2 += ex * ex / (p.point.sigma_x_px * p.point.sigma_x_px) + ey * ey / (p.point.sigma_y_px * p.point.sigma_y_px);
  }
  EXPECT_LT(std::sqrt(n2 / (2.0 * listed)), 1.4);
  const PasspointPoint& nothing = found.points[listed];
  EXPECT_EQ(nothing.point.id, "nothing-here");
  EXPECT_EQ(nothing.point.status, PointStatus::kMissing);
  EXPECT_EQ(nothing.point.reason, "not_found");
  EXPECT_EQ(nothing.point.sigma_x_px, 0.0);  // the listed position, never a measurement
  EXPECT_EQ(nothing.point.position_px.x_px, empty.x_px);
  EXPECT_EQ(found.points[listed + 1].point.status, PointStatus::kMissing);
  EXPECT_EQ(found.points[listed + 1].point.reason, "outside_scan");
  EXPECT_EQ(found.points[listed + 2].point.status, PointStatus::kMissing);
  EXPECT_EQ(found.points[listed + 2].point.reason, "not_found");
  EXPECT_EQ(found.masked, 1);
  EXPECT_EQ(found.measured, static_cast<int>(listed));
  EXPECT_EQ(found.missing, 3);

  // The two closest passpoints, clicked half-way between, with a window reaching both.
  size_t a = 0, b = 1;
  for (size_t i = 0; i < r.truth.size(); ++i)
    for (size_t j = i + 1; j < r.truth.size(); ++j)
      if (std::hypot(*r.truth[i].x_px - *r.truth[j].x_px, *r.truth[i].y_px - *r.truth[j].y_px) <
          std::hypot(*r.truth[a].x_px - *r.truth[b].x_px, *r.truth[a].y_px - *r.truth[b].y_px))
        a = i, b = j;
  const double d = std::hypot(*r.truth[a].x_px - *r.truth[b].x_px, *r.truth[a].y_px - *r.truth[b].y_px);
  options.mask.clear();
  options.search_radius_px = 0.5 * d + 10.0;
  const std::vector<ApproximatePasspoint> between{
      {"between", {0.5 * (*r.truth[a].x_px + *r.truth[b].x_px), 0.5 * (*r.truth[a].y_px + *r.truth[b].y_px)}}};
  const PasspointDetection two = DetectPasspoints(image, options, &between);
  ASSERT_EQ(two.points.size(), 1u);
  EXPECT_EQ(two.points[0].point.status, PointStatus::kRejected);
  EXPECT_EQ(two.points[0].point.reason, "ambiguous");
  // A window reaching only the first finds it alone.
  options.search_radius_px = 20.0;
  const std::vector<ApproximatePasspoint> near{{"near", {*r.truth[a].x_px + 5.0, *r.truth[a].y_px}}};
  EXPECT_EQ(DetectPasspoints(image, options, &near).points[0].point.status, PointStatus::kMeasured);
}

// Distractors of the same size and polarity: bright rings (as bright as the
// format corners' lines) among bright dust disks of 150-350 um and scratches.
TEST(PasspointDetector, BrightRingsAmongDustOfTheSameSize) {
  TempDir dir;
  std::string spec = BundledSpec();
  spec.replace(spec.find("count = 40"), 10, "count = 24");  // fewer fits: a shorter test
  spec.replace(spec.find("polarity = \"dark\"\ncontrast_dn = 60.0\ncount"), 17, "polarity = \"bright\"");
  const RenderedPasspoints r = RenderPasspoints(spec +
                                "\n[defects]\ndust_count = 40\ndust_diameter_min_um = 150.0\ndust_diameter_max_um = 350.0\n"
                                "dust_contrast_dn = 60.0\nscratch_count = 4\nscratch_width_um = 40.0\n"
                                "dust_polarity = \"bright\"\nscratch_contrast_dn = 40.0\nscratch_polarity = \"bright\"\n",
                            dir);
  const Image image = Image::Open(r.image_path);
  PasspointDetectorOptions options = RingOptions(r.pixel_size_um);
  options.dark = false;
  const PasspointDetection found = DetectPasspoints(image, options);
  std::printf("%s\n", found.summary.c_str());
  const Comparison c = Compare(found, r.truth);
  // Rings touched by dust may be rejected (or lost); every clean one is measured.
  const auto [clean, clean_found] = CleanMarks(r, c, 6.25);
  std::printf("clean rings %d, measured %d; RMS/CRB %.3f, RMS error/sigma %.3f\n", clean, clean_found,
              c.rms_error_px / c.rms_crb_px, c.rms_normalized);
  EXPECT_GE(clean, 20);
  EXPECT_EQ(clean_found, clean);
  EXPECT_EQ(c.false_points, 0);  // no dust disk is a ring
  EXPECT_EQ(c.duplicates, 0);
  EXPECT_GT(found.not_passpoints, 0);  // the dust was seen and refused
  EXPECT_LE(c.rms_error_px / c.rms_crb_px, 1.3);
}

// The dot variant: 200 um dark dots among smaller dust (40-120 um), 25 um pixels.
TEST(PasspointDetector, DotsAmongSmallerDust) {
  std::string spec = BundledSpec();
  spec.replace(spec.find("shape = \"ring\""), 14, "shape = \"dot\"");
  spec.replace(spec.find("diameter_um = 250.0"), 19, "diameter_um = 200.0");
  spec.replace(spec.find("pixel_size_um = 20.0"), 20, "pixel_size_um = 25.0");
  spec.replace(spec.find("count = 40"), 10, "count = 24");
  spec += "\n[defects]\ndust_count = 40\ndust_diameter_min_um = 40.0\ndust_diameter_max_um = 120.0\ndust_contrast_dn = 60.0\n";
  TempDir dir;
  const RenderedPasspoints r = RenderPasspoints(spec, dir);
  ASSERT_EQ(r.truth.size(), 25u);
  const Image image = Image::Open(r.image_path);
  PasspointDetectorOptions options;
  options.shape = MarkType::kDot;
  options.diameter_px = 200.0 / r.pixel_size_um;
  const PasspointDetection found = DetectPasspoints(image, options);
  std::printf("%s\n", found.summary.c_str());
  const Comparison c = Compare(found, r.truth);
  const auto [clean, clean_found] = CleanMarks(r, c, 4.0);
  std::printf("clean dots %d, measured %d; RMS error %.4f px, RMS CRB %.4f px, RMS/CRB %.3f, RMS error/sigma %.3f\n",
              clean, clean_found, c.rms_error_px, c.rms_crb_px, c.rms_error_px / c.rms_crb_px, c.rms_normalized);
  EXPECT_GE(clean, 20);
  EXPECT_EQ(clean_found, clean);
  EXPECT_EQ(c.false_points, 0);
  EXPECT_EQ(c.duplicates, 0);
  EXPECT_LE(c.rms_error_px / c.rms_crb_px, 1.3);
  EXPECT_GT(c.rms_normalized, 0.7);
  EXPECT_LT(c.rms_normalized, 1.3);
}

// Marks that are there but not good: list mode says so with the reason, and
// keeps the fitted position (never measured). The bundled plate with three of
// its rings altered in the scene before rendering.
TEST(PasspointDetector, ListModeRejectsFaintThickAndDamagedRings) {
  const DefinitionRegistry registry;
  sim::SimulatedPlate plate = sim::BuildSimulatedPlate(sim::ParseSimulationSpec(BundledSpec(), "spec"), registry);
  std::vector<size_t> rings;  // truth indices of passpoints
  for (size_t i = 0; i < plate.truth.size(); ++i)
    if (plate.truth[i].kind == PointKind::kPasspoint && plate.truth_mark[i] >= 0) rings.push_back(i);
  ASSERT_GE(rings.size(), 4u);
  auto mark_of = [&](size_t k) -> sim::SceneMark& {
    return plate.scene.marks[static_cast<size_t>(plate.truth_mark[rings[k]])];
  };
  mark_of(0).amplitude_dn = -10.0;    // faint: about 3 x the noise
  mark_of(1).line_width_um = 75.0;    // 1.5 x too thick: not the ring we look for
  sim::SceneMark speck = mark_of(2);  // dust on the third ring's line
  speck.id = "speck";
  speck.kind = sim::MarkKind::kDust;
  speck.shape = sim::MarkShapeKind::kDot;
  speck.size_um = 200.0;
  speck.amplitude_dn = 60.0;          // bright: it blots out part of the dark line
  speck.centre_px.x_px += 6.0;
  plate.scene.marks.push_back(speck);
  TempDir dir;
  const PixelPoint truth[4] = {{*plate.truth[rings[0]].x_px, *plate.truth[rings[0]].y_px},
                               {*plate.truth[rings[1]].x_px, *plate.truth[rings[1]].y_px},
                               {*plate.truth[rings[2]].x_px, *plate.truth[rings[2]].y_px},
                               {*plate.truth[rings[3]].x_px, *plate.truth[rings[3]].y_px}};
  const double pixel_size_um = plate.pixel_size_um;
  const Image image = Image::Open(sim::WriteSimulatedPlate(std::move(plate), dir.path().string()).image_path);
  std::vector<ApproximatePasspoint> list;
  for (int k = 0; k < 4; ++k) list.push_back({"R" + std::to_string(k), {truth[k].x_px + 3.0, truth[k].y_px - 2.0}});
  const PasspointDetection found = DetectPasspoints(image, RingOptions(pixel_size_um), &list);
  std::printf("%s\n", found.summary.c_str());
  ASSERT_EQ(found.points.size(), 4u);
  for (const PasspointPoint& p : found.points)
    std::printf("%s: %s %s, fit %s\n", p.point.id.c_str(), PointStatusName(p.point.status), p.point.reason.c_str(),
                p.fit.summary.c_str());
  EXPECT_EQ(found.points[0].point.status, PointStatus::kRejected);
  EXPECT_EQ(found.points[0].point.reason, "low_contrast");
  EXPECT_EQ(found.points[1].point.status, PointStatus::kRejected);
  EXPECT_EQ(found.points[1].point.reason, "poor_fit");
  EXPECT_EQ(found.points[2].point.status, PointStatus::kRejected);
  EXPECT_EQ(found.points[2].point.reason, "defect");
  EXPECT_EQ(found.points[3].point.status, PointStatus::kMeasured);  // an untouched one
  // A rejected mark carries where its fit put it, with sigmas: the thick ring's centre is still its centre.
  EXPECT_LT(std::hypot(found.points[1].point.position_px.x_px - truth[1].x_px,
                       found.points[1].point.position_px.y_px - truth[1].y_px), 0.5);
  EXPECT_GT(found.points[1].point.sigma_x_px, 0.0);
}

TEST(PasspointList, ParsesCommentsAndBlankLines) {
  const std::vector<ApproximatePasspoint> list =
      ParsePasspointList("# clicked on the overview\nid,x_px,y_px\n\nPUG-1, 1450.5 ,1466\n  # second\nB7,12,-3.25\n", "l.csv");
  ASSERT_EQ(list.size(), 2u);
  EXPECT_EQ(list[0].id, "PUG-1");
  EXPECT_EQ(list[0].position_px.x_px, 1450.5);
  EXPECT_EQ(list[0].position_px.y_px, 1466.0);
  EXPECT_EQ(list[1].id, "B7");
  EXPECT_EQ(list[1].position_px.y_px, -3.25);
}

std::string ErrorOf(const std::string& text) {
  try {
    ParsePasspointList(text, "points.csv");
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(PasspointList, BadFilesFailWithFileAndLine) {
  EXPECT_NE(ErrorOf("id,x,y\nA,1,2\n").find("points.csv"), std::string::npos);
  EXPECT_NE(ErrorOf("id,x,y\nA,1,2\n").find("line 1: expected the header 'id,x_px,y_px'"), std::string::npos);
  EXPECT_NE(ErrorOf("# c\nid,x_px,y_px\nA,1,2\nB,1\n").find("line 4: expected 3 fields"), std::string::npos);
  EXPECT_NE(ErrorOf("id,x_px,y_px\nA,1,two\n").find("line 2: y_px 'two' is not a number"), std::string::npos);
  EXPECT_NE(ErrorOf("id,x_px,y_px\nA,1,2\nA,3,4\n").find("line 3: duplicate id 'A'"), std::string::npos);
  EXPECT_NE(ErrorOf("id,x_px,y_px\n,1,2\n").find("line 2: empty id"), std::string::npos);
  EXPECT_NE(ErrorOf("id,x_px,y_px\nA,nan,2\n").find("x_px 'nan' is not a number"), std::string::npos);
  EXPECT_NE(ErrorOf("id,x_px,y_px\n# nothing\n").find("no passpoints"), std::string::npos);
  EXPECT_NE(ErrorOf("").find("no header"), std::string::npos);
  TempDir dir;
  try {
    ReadPasspointList(dir.file("absent.csv"));
    ADD_FAILURE() << "no error for a missing file";
  } catch (const Error& e) {
    EXPECT_EQ(e.subject(), dir.file("absent.csv"));
  }
}

TEST(PasspointDetector, OptionsChecked) {
  PasspointDetectorOptions options;
  std::string why;
  EXPECT_FALSE(options.Check(&why));  // no diameter
  EXPECT_NE(why.find("diameter_px"), std::string::npos);
  options.diameter_px = 12.5;
  EXPECT_FALSE(options.Check(&why));  // a ring without its line width
  options.line_width_px = 2.5;
  EXPECT_TRUE(options.Check(&why)) << why;
  options.shape = MarkType::kCross;
  EXPECT_FALSE(options.Check(&why));
}

// Issue #28: a byte order mark accepted; ids valid UTF-8 without control
// characters; positions range-checked.
TEST(PasspointList, AByteOrderMarkIsAccepted) {
  // Reported: a list saved with a BOM was refused, the message quoting the invisible BOM.
  const std::vector<ApproximatePasspoint> list = ParsePasspointList("\xEF\xBB\xBFid,x_px,y_px\nA,1,2\n", "points.csv");
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].id, "A");
}

TEST(PasspointList, IdsThatAreNotUtf8OrHoldControlCharactersAreRefused) {
  // Reported: a non-UTF-8 id made micmac.xml ill-formed later.
  EXPECT_EQ(ErrorOf("id,x_px,y_px\nP\xff,1,2\n"), "points.csv: line 2: the id byte 0xff at position 2 is not valid UTF-8");
  EXPECT_EQ(ErrorOf("id,x_px,y_px\nP\x1b[31m,1,2\n"),
            "points.csv: line 2: the id contains the control character 0x1b at position 2");
  EXPECT_EQ(ParsePasspointList("id,x_px,y_px\n\xe2\x98\x85,1,2\n", "points.csv")[0].id, "\xe2\x98\x85");  // a star sign
}

TEST(PasspointList, PositionsOutsideTheAcceptedRangeAreRefused) {
  EXPECT_EQ(ErrorOf("id,x_px,y_px\nA,1e307,2\n"),
            "points.csv: line 2: x_px '1e307' is outside the accepted range -1e7..1e7 px");
  EXPECT_EQ(ErrorOf("id,x_px,y_px\nA,1,-2e7\n"), "points.csv: line 2: y_px '-2e7' is outside the accepted range -1e7..1e7 px");
}

}  // namespace
}  // namespace platemeter
