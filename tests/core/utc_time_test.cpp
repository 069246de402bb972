// ParseUtcIso8601 (core/utc_time.h): a fuzz finding (a 50 000-digit time overflowed the
// stack inside std::regex) is a one-line error; ordinary times still parse.
#include "platemeter/core/utc_time.h"

#include <gtest/gtest.h>

#include <string>

#include "platemeter/core/error.h"

namespace platemeter {
namespace {

TEST(UtcTime, AHugeStringIsAnErrorNotACrash) {
  const std::string huge = "1972-05-12T05:30:" + std::string(50000, '1');
  try {
    ParseUtcIso8601(huge);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.reason(), "not an ISO 8601 UTC time (50017 characters; at most 64)");
  }
}

TEST(UtcTime, ALongButValidTimeParses) {
  // 64 characters: the longest accepted.
  const std::string text = "1972-05-12T05:30:00." + std::string(43, '0') + "Z";
  ASSERT_EQ(text.size(), 64u);
  const UtcInstant a = ParseUtcIso8601(text), b = ParseUtcIso8601("1972-05-12T05:30:00Z");
  EXPECT_EQ(a.jd1 + a.jd2, b.jd1 + b.jd2);
}

}  // namespace
}  // namespace platemeter
