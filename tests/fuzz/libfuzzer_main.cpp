// Coverage-guided entry for clang's libFuzzer (docs/fuzzing.md), built only
// with -DPLATEMETER_LIBFUZZER=ON. The reader is chosen by the environment:
//   PLATEMETER_FUZZ_TARGET=measurement_file ./platemeter_libfuzzer CORPUS_DIR
// With PLATEMETER_FUZZ_WRITE_SEEDS=DIR the reader's seeds (fuzz_targets.h:
// the corpus files, built-in definitions, generated TIFFs) are written to DIR
// first, so DIR can be the corpus.
// platemeter::Error is the expected rejection; any other exception aborts, which
// libFuzzer reports as a crash with its input.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz/fuzz_targets.h"
#include "platemeter/core/error.h"
#include "platemeter/core/log.h"

namespace {

const platemeter::fuzz::FuzzTarget* g_target = nullptr;

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  platemeter::SetWarningSink([](const std::string&) {});  // accepted odd inputs warn; keep the output readable
  const char* name = std::getenv("PLATEMETER_FUZZ_TARGET");
  try {
    g_target = &platemeter::fuzz::TargetNamed(name ? name : "");
  } catch (const std::exception&) {
    std::fprintf(stderr, "set PLATEMETER_FUZZ_TARGET to one of:");
    for (const auto& t : platemeter::fuzz::AllTargets()) std::fprintf(stderr, " %s", t.name.c_str());
    std::fprintf(stderr, "\n");
    std::exit(2);
  }
  if (const char* dir = std::getenv("PLATEMETER_FUZZ_WRITE_SEEDS"); dir && *dir) {
    std::filesystem::create_directories(dir);
    int n = 0;
    for (const std::string& seed : platemeter::fuzz::SeedsOf(*g_target)) {
      std::ofstream(std::filesystem::path(dir) / ("seed-" + std::to_string(n++)), std::ios::binary) << seed;
    }
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    g_target->run(bytes);
  } catch (const platemeter::Error&) {
    // expected: the input is rejected with a message
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz finding: %s\n", e.what());
    std::abort();
  }
  return 0;
}
