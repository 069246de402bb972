// Star catalog reader against public catalog values typed from memory of the
// Hipparcos catalogue (ICRS, J2000.0 positions, Hipparcos V magnitudes, HD numbers).
// The catalog comes from Debian's kstars-data: when it is missing these tests
// FAIL with an install hint (the project's setup installs it), they do not skip.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <set>

#include "platemeter/calib/star_catalog.h"
#include "platemeter/core/error.h"
#include "support/test_support.h"
#include "platemeter/core/angles.h"
#include "support/sexagesimal.h"

namespace platemeter::calib {
namespace {

using testing::Dms;
using testing::Hms;

struct KnownStar {
  const char* name;
  double ra_rad, dec_rad, v_mag;
  int hd;
};

// Hipparcos J2000 positions and V magnitudes.
const KnownStar kKnown[] = {
    {"Vega", Hms(18, 36, 56.336), Dms(+1, 38, 47, 1.28), 0.03, 172167},
    {"Polaris", Hms(2, 31, 49.095), Dms(+1, 89, 15, 50.79), 1.97, 8890},
    {"Sirius", Hms(6, 45, 8.917), Dms(-1, 16, 42, 58.02), -1.44, 48915},
    {"Arcturus", Hms(14, 15, 39.672), Dms(+1, 19, 10, 56.68), -0.05, 124897},
    {"Rigel", Hms(5, 14, 32.272), Dms(-1, 8, 12, 5.90), 0.18, 34085},
    {"Deneb", Hms(20, 41, 25.915), Dms(+1, 45, 16, 49.22), 1.25, 197345},
};

bool CatalogPresent(const std::string& path) { return std::filesystem::is_regular_file(path); }
std::string InstallHint(const std::string& path) {
  return path + " is missing: install Debian package kstars-data (scripts/setup does)";
}

// Nearest star to a direction among those brighter than `brighter_than`.
const CatalogStar* Nearest(const std::vector<CatalogStar>& stars, double ra, double dec, double brighter_than) {
  const CatalogStar* best = nullptr;
  double best_sep = 1e9;
  for (const auto& s : stars) {
    if (s.v_mag > brighter_than) continue;
    const double sep = AngularSeparation(s.ra_rad, s.dec_rad, ra, dec);
    if (sep < best_sep) best_sep = sep, best = &s;
  }
  return best_sep < 60 * kRadPerArcsec ? best : nullptr;
}

// The whole catalog, loaded once; a load error fails the test that asked.
class StarCatalogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(CatalogPresent(DefaultStarCatalogPath())) << InstallHint(DefaultStarCatalogPath());
    if (!sky_) {
      StarQueryOptions all;
      all.faint_limit_mag = 99.0;
      sky_ = std::make_unique<std::vector<CatalogStar>>(LoadStarCatalog(DefaultStarCatalogPath(), all));
    }
  }
  static std::unique_ptr<std::vector<CatalogStar>> sky_;
};
std::unique_ptr<std::vector<CatalogStar>> StarCatalogTest::sky_;

TEST_F(StarCatalogTest, BrightStarsAtHipparcosPositions) {
  for (const KnownStar& k : kKnown) {
    const CatalogStar* s = Nearest(*sky_, k.ra_rad, k.dec_rad, 3.0);
    ASSERT_NE(s, nullptr) << k.name << " not found within 60 arcsec";
    EXPECT_LT(AngularSeparation(s->ra_rad, s->dec_rad, k.ra_rad, k.dec_rad) / kRadPerArcsec, 1.0) << k.name;
    EXPECT_NEAR(s->v_mag, k.v_mag, 0.1) << k.name;
    EXPECT_EQ(s->name, k.name);
  }
}

TEST_F(StarCatalogTest, ProperMotionIncludesCosDec) {
  // Arcturus, Hipparcos: mu_alpha* = -1093.45 mas/yr (cos dec included), mu_delta = -1999.40.
  const CatalogStar* arcturus = Nearest(*sky_, kKnown[3].ra_rad, kKnown[3].dec_rad, 1.0);
  ASSERT_NE(arcturus, nullptr);
  EXPECT_NEAR(arcturus->pm_ra_mas_yr, -1093.45, 1.0);
  EXPECT_NEAR(arcturus->pm_dec_mas_yr, -1999.40, 1.0);
  EXPECT_NEAR(arcturus->parallax_mas, 88.85, 0.5);
  EXPECT_EQ(arcturus->spectral_type, "K2");
  // Polaris (dec 89.26 deg): mu_alpha* = 44.22 mas/yr; without cos dec it would be ~3400.
  const CatalogStar* polaris = Nearest(*sky_, kKnown[1].ra_rad, kKnown[1].dec_rad, 3.0);
  ASSERT_NE(polaris, nullptr);
  EXPECT_NEAR(polaris->pm_ra_mas_yr, 44.2, 1.0);
}

TEST_F(StarCatalogTest, NakedEyeStarCount) {
  // About 5000 stars are brighter than V = 6 over the whole sky (Bright Star
  // Catalogue: ~9100 to V = 6.5, ~5000 to V = 6.0).
  const auto n = std::count_if(sky_->begin(), sky_->end(), [](const CatalogStar& s) { return s.v_mag <= 6.0; });
  EXPECT_GT(n, 4000);
  EXPECT_LT(n, 6000);
  // The whole-sky load honours the magnitude limit.
  StarQueryOptions q;
  q.faint_limit_mag = 6.0;
  EXPECT_EQ(static_cast<long>(LoadStarCatalog(DefaultStarCatalogPath(), q).size()), n);
}

TEST_F(StarCatalogTest, ConeQueryEqualsBruteForce) {
  StarQueryOptions q;
  q.whole_sky = false;
  q.faint_limit_mag = 8.0;
  q.center_ra_rad = Hms(5, 35, 0);  // Orion
  q.center_dec_rad = Dms(-1, 5, 0, 0);
  q.radius_rad = 12.0 * std::numbers::pi / 180;
  const auto cone = LoadStarCatalog(DefaultStarCatalogPath(), q);
  std::set<int64_t> got, want;
  for (const auto& s : cone) got.insert(s.id);
  for (const auto& s : *sky_)
    if (s.v_mag <= 8.0 && AngularSeparation(s.ra_rad, s.dec_rad, q.center_ra_rad, q.center_dec_rad) <= q.radius_rad)
      want.insert(s.id);
  EXPECT_GT(want.size(), 500u);  // a 12-degree cone to V = 8 holds hundreds of stars
  EXPECT_EQ(got, want);
  EXPECT_EQ(cone.size(), want.size());
}

TEST_F(StarCatalogTest, BinaryStarDataFileAgrees) {
  // kstars-data also ships the binary starData layout (namedstars.dat): same
  // stars, with HD numbers as ids; positions stored at J1991.25, returned at
  // J2000. Its magnitudes are not Johnson V for the brightest stars (Arcturus
  // 0.16), so only positions and ids are compared.
  const std::string named = "/usr/share/kstars/namedstars.dat";
  ASSERT_TRUE(CatalogPresent(named)) << InstallHint(named);
  StarQueryOptions q;
  q.faint_limit_mag = 3.0;
  const auto stars = LoadStarCatalog(named, q);
  for (const KnownStar& k : kKnown) {
    const CatalogStar* s = Nearest(stars, k.ra_rad, k.dec_rad, 3.0);
    ASSERT_NE(s, nullptr) << k.name;
    EXPECT_TRUE(s->id_is_hd) << k.name;
    EXPECT_EQ(s->id, k.hd) << k.name;
    EXPECT_LT(AngularSeparation(s->ra_rad, s->dec_rad, k.ra_rad, k.dec_rad) / kRadPerArcsec, 1.0) << k.name;
  }
}

TEST(StarCatalogErrors, MissingFileNamesFileAndReason) {
  try {
    LoadStarCatalog("/nonexistent/stars.dat", StarQueryOptions{});
    FAIL() << "no error for a missing file";
  } catch (const Error& e) {
    EXPECT_EQ(e.subject(), "/nonexistent/stars.dat");
    EXPECT_NE(std::string(e.what()).find("not found"), std::string::npos) << e.what();
  }
}

TEST(StarCatalogErrors, MalformedTextLine) {
  testing::TempDir dir;
  const std::string path = dir.file("bad.dat");
  {
    std::ofstream f(path);
    f << "# header\n";
    f << "064508.92 -164258.0 -000546.0-001223.100379.2 -1.4400.01A0 1            , alp CMa, Sirius\n";
    f << "1845xx.00 +384701.3 +000201.0+000287.500128.9 00.03-0.00A0 0\n";
  }
  try {
    LoadStarCatalog(path, StarQueryOptions{});
    FAIL() << "no error for a malformed line";
  } catch (const Error& e) {
    EXPECT_EQ(e.subject(), path);
    EXPECT_NE(e.reason().find("line 3"), std::string::npos) << e.what();
    EXPECT_NE(e.reason().find("RA"), std::string::npos) << e.what();
  }
}

TEST(StarCatalogErrors, TruncatedBinaryAndGarbage) {
  testing::TempDir dir;
  const std::string named = "/usr/share/kstars/namedstars.dat";
  ASSERT_TRUE(CatalogPresent(named)) << InstallHint(named);
  const std::string cut = dir.file("cut.dat");
  {
    std::ifstream in(named, std::ios::binary);
    std::string head(2000, '\0');
    in.read(head.data(), head.size());
    std::ofstream(cut, std::ios::binary) << head;
  }
  EXPECT_THROW(LoadStarCatalog(cut, StarQueryOptions{}), Error);
  const std::string junk = dir.file("junk.dat");
  std::ofstream(junk, std::ios::binary) << std::string("\x7f" "ELF garbage", 11);
  EXPECT_THROW(LoadStarCatalog(junk, StarQueryOptions{}), Error);
  StarQueryOptions bad;
  bad.whole_sky = false;
  bad.radius_rad = -1.0;
  std::string why;
  EXPECT_FALSE(bad.Check(&why));
}

TEST(RandomStarField, SeededConeAndMagnitudes) {
  RandomStarFieldOptions o;
  o.seed = 42;
  o.count = 3000;
  o.center_ra_rad = 1.0;
  o.center_dec_rad = 0.6;
  o.radius_rad = 0.2;
  const auto a = GenerateRandomStarField(o);
  const auto b = GenerateRandomStarField(o);
  ASSERT_EQ(a.size(), 3000u);
  int inner = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].ra_rad, b[i].ra_rad);
    const double sep = AngularSeparation(a[i].ra_rad, a[i].dec_rad, o.center_ra_rad, o.center_dec_rad);
    ASSERT_LE(sep, o.radius_rad + 1e-12);
    ASSERT_GE(a[i].v_mag, o.bright_mag);
    ASSERT_LE(a[i].v_mag, o.faint_mag);
    if (sep < o.radius_rad / std::sqrt(2.0)) ++inner;  // half the cap's area (small-cap approximation)
  }
  EXPECT_NEAR(inner / 3000.0, 0.5, 0.05);  // uniform on the sphere
  o.seed = 43;
  EXPECT_NE(GenerateRandomStarField(o)[0].ra_rad, a[0].ra_rad);
  o.radius_rad = 0.0;
  EXPECT_THROW(GenerateRandomStarField(o), Error);
}

}  // namespace
}  // namespace platemeter::calib
