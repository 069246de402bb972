// The fuzz harness under ctest (docs/fuzzing.md): every reader runs on
// mutations of its seed corpus for PLATEMETER_FUZZ_SECONDS (6 s by default,
// so ten readers add about a minute to the suite). A finding fails the test and
// names the saved input; a crash or hang ends the test process after saving it.
#include <gtest/gtest.h>

#include <iostream>
#include <stdexcept>

#include "fuzz/fuzz_driver.h"
#include "fuzz/fuzz_targets.h"
#include "fuzz/mutator.h"
#include "platemeter/core/error.h"
#include "platemeter/core/log.h"

namespace platemeter::fuzz {
namespace {

constexpr double kCiSecondsPerReader = 3.0;

void FuzzReader(const std::string& name) {
  const FuzzTarget& target = TargetNamed(name);
  const std::vector<std::string> seeds = SeedsOf(target);
  ASSERT_FALSE(seeds.empty()) << "no seeds for " << name;
  long warnings = 0;  // accepted odd inputs warn (e.g. an RGB scan): counted, not printed
  SetWarningSink([&warnings](const std::string&) { ++warnings; });
  // The seeds are valid inputs: fuzzing starts from files the reader accepts.
  for (size_t i = 0; i < seeds.size(); ++i) {
    EXPECT_NO_THROW(target.run(seeds[i])) << name << " seed " << i;
  }
  const FuzzOptions options = OptionsFromEnvironment(kCiSecondsPerReader);
  const FuzzReport report = RunFuzz(target, seeds, options);
  SetWarningSink(nullptr);
  std::cout << "fuzz " << name << ": " << report.inputs << " inputs in " << options.seconds << " s (seed "
            << options.seed << "): " << report.accepted << " accepted, " << report.rejected << " rejected, "
            << report.findings.size() << " findings, " << warnings << " warnings (this process)\n";
  EXPECT_GT(report.rejected, 0);  // the mutations do reach the checks
  for (const std::string& finding : report.findings) ADD_FAILURE() << name << ": " << finding;
}

TEST(Fuzz, MeasurementFile) { FuzzReader("measurement_file"); }
TEST(Fuzz, Definitions) { FuzzReader("definitions"); }
TEST(Fuzz, JobFile) { FuzzReader("job_file"); }
TEST(Fuzz, PasspointList) { FuzzReader("passpoint_list"); }
TEST(Fuzz, ObservationsCsv) { FuzzReader("observations_csv"); }
TEST(Fuzz, GroundPointsCsv) { FuzzReader("ground_points_csv"); }
TEST(Fuzz, ScanManifest) { FuzzReader("scan_manifest"); }
TEST(Fuzz, StellarJob) { FuzzReader("stellar_job"); }
TEST(Fuzz, BundleJob) { FuzzReader("bundle_job"); }
TEST(Fuzz, TiffHeader) { FuzzReader("tiff_header"); }

// The harness itself: the same seed gives the same inputs, and an exception
// other than platemeter::Error is reported as a finding.
TEST(FuzzHarness, MutationsRepeatForTheSameSeed) {
  const std::vector<std::string> seeds = {"id,x_px,y_px\nA,1.5,2\n"};
  Mutator a(7), b(7), c(8);
  bool differs = false;
  for (int i = 0; i < 200; ++i) {
    const std::string from_a = a.MutateText(seeds[0], seeds);
    EXPECT_EQ(from_a, b.MutateText(seeds[0], seeds));
    differs = differs || from_a != c.MutateText(seeds[0], seeds);
  }
  EXPECT_TRUE(differs);
}

TEST(FuzzHarness, NumbersAreFoundForReplacement) {
  const std::string text = "x = 1.5e-3, y=-2 name=\"X1Y1\" 7";
  std::vector<std::string> found;
  for (const auto& [begin, end] : NumberTokens(text)) found.push_back(text.substr(begin, end - begin));
  EXPECT_EQ(found, (std::vector<std::string>{"1.5e-3", "-2", "7"}));
}

// A harness bug the long run found: an IFD offset of 0xffffffff wrapped in
// 32-bit arithmetic and the TIFF mutator read far outside the input.
TEST(FuzzHarness, TiffMutationsSurviveAnyIfdOffset) {
  std::string tiff("II*\0\xff\xff\xff\xff\x11\x00", 10);
  tiff += std::string(400, '\x01');
  Mutator mutator(3);
  for (int i = 0; i < 20000; ++i) EXPECT_LE(mutator.MutateTiff(tiff).size(), Mutator::max_bytes);
  tiff.replace(4, 4, std::string("\xfe\xff\xff\xff", 4));
  for (int i = 0; i < 20000; ++i) EXPECT_LE(mutator.MutateTiff(tiff).size(), Mutator::max_bytes);
}

void ThrowsLogicErrorOnComma(const std::string& bytes) {
  if (bytes.find(',') != std::string::npos) throw std::logic_error("planted bug");
  throw Error("planted", "rejected");
}

TEST(FuzzHarness, ANonErrorExceptionIsAFinding) {
  FuzzOptions options;
  options.max_inputs = 300;
  options.seconds = 30;
  options.crash_dir = ::testing::TempDir();
  const FuzzReport report = RunFuzz({"planted", ThrowsLogicErrorOnComma}, {"abc"}, options);
  EXPECT_EQ(report.inputs, 300);
  EXPECT_GT(report.rejected, 0);
  ASSERT_FALSE(report.findings.empty());  // the mutations insert commas
  EXPECT_NE(report.findings[0].find("planted bug"), std::string::npos) << report.findings[0];
}

}  // namespace
}  // namespace platemeter::fuzz
