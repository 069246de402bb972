#pragma once
// What every text reader (CSV, TOML, the measurement file) checks where input
// enters (issue #28): a leading UTF-8 byte order mark is dropped, text fields
// are valid UTF-8 without control characters (they end up in XML, CSV and
// HTML outputs), and numbers lie in their documented, physically meaningful
// range (an absurd value fails here, naming file and line, instead of
// overflowing to inf in an adjustment later).
#include <string>
#include <string_view>

namespace platemeter {

// `text` without a leading UTF-8 byte order mark (spreadsheets write one).
std::string_view WithoutUtf8Bom(std::string_view text);

// Length of the UTF-8 sequence starting at s[i], or 0 if it is not valid
// (RFC 3629: shortest form only, no surrogates, at most U+10FFFF).
size_t Utf8SequenceLength(std::string_view s, size_t i);

// Empty when `field` is valid UTF-8 (no overlong forms, surrogates or code
// points above U+10FFFF) without control characters (U+0000..U+001F, U+007F);
// else why not, e.g. "byte 0xff at position 3 is not valid UTF-8".
std::string TextFieldProblem(std::string_view field);

// A closed range of accepted values, with the unit for messages.
struct NumberRange {
  double min = 0.0;
  double max = 0.0;
  const char* unit = "";  // "px", "mm", "" (dimensionless)

  bool Contains(double value) const { return value >= min && value <= max; }  // false for NaN
  // "-1e7..1e7 px"
  std::string Describe() const;
};

// A number in its shortest exact form, exponent without '+' and leading
// zeros: 1e7, -1e-5, 0.25.
std::string ShortNumber(double value);

// "'<as_written>' is outside the accepted range <range>", the reason a reader
// adds to its file and line.
std::string OutsideRange(const std::string& as_written, const NumberRange& range);

}  // namespace platemeter
