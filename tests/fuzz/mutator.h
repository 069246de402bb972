#pragma once
// Deterministic mutations for the fuzz harness (docs/fuzzing.md): what breaks
// text readers (numbers replaced by extremes, lines and fields deleted or
// duplicated, byte order marks, invalid UTF-8, CR/LF changes, truncation) and,
// for TIFF, the header's IFD entries set to extreme counts, offsets and types.
// The same seed gives the same sequence of inputs.
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace platemeter::fuzz {

class Mutator {
 public:
  explicit Mutator(uint64_t seed) : random_(seed) {}

  // `input` changed by 1..4 stacked mutations; `others` (may be empty) are
  // spliced in now and then. Never longer than max_bytes.
  std::string MutateText(const std::string& input, const std::vector<std::string>& others);
  std::string MutateTiff(const std::string& input);

  // A uniform index in [0, n).
  size_t Below(size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<size_t>(0, n - 1)(random_); }

  static constexpr size_t max_bytes = 1 << 16;  // as libFuzzer's -max_len in docs/fuzzing.md; larger inputs only slow it

 private:
  void TextStep(std::string& text, const std::vector<std::string>& others);
  void TiffStep(std::string& bytes);
  std::mt19937_64 random_;
};

// The byte ranges of the number-like tokens of `text` ([-+]?digit..., also
// inf/nan words), for replacing them with extremes.
std::vector<std::pair<size_t, size_t>> NumberTokens(const std::string& text);

}  // namespace platemeter::fuzz
