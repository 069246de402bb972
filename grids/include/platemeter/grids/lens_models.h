#pragma once
// The lens models a definition file may name, with the coefficient keys each
// one needs (docs/definitions.md). The reader checks a camera's lens against
// this list so that a misspelt or missing coefficient is an error, not a zero.
#include <string>
#include <vector>

namespace platemeter {

struct LensCoefficientInfo {
  std::string key;      // as written in [camera.lens.coefficients]; the suffix is the unit
  std::string meaning;  // one line, for docs and messages
};

struct LensModelInfo {
  std::string name;    // "smac-radial-decentering", "brown-balanced", "orbigon-11"
  std::string source;  // the seed and equations that define it
  std::vector<LensCoefficientInfo> coefficients;  // every one is required
};

const std::vector<LensModelInfo>& KnownLensModels();
// nullptr for an unknown name.
const LensModelInfo* FindLensModel(const std::string& name);
// "a, b, c": the known model names, for error messages.
std::string KnownLensModelNames();

}  // namespace platemeter
