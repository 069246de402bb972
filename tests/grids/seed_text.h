#pragma once
// Reads values straight from the seed text files (the OCR'd source documents),
// independently of grids/builtin/*.toml, so the tests compare the built-ins
// with what the documents print.
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace platemeter::testing {

inline std::string ReadSeed(const std::string& file) {
  std::ifstream in(std::string(PLATEMETER_SEEDS_DIR) + "/" + file);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

inline std::vector<std::string> SplitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream stream(text);
  std::string line;
  while (std::getline(stream, line)) lines.push_back(line);
  return lines;
}

// "- 9.9990" -> "-9.9990", "1,063.6" -> "1063.6".
inline std::string Squeeze(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c != ' ' && c != ',' && c != '\t') out += c;
  }
  return out;
}

struct SeedPoint {
  double x_mm = 0.0;
  double y_mm = 0.0;
};

// Seed 004 Tables A.1 (both sheets) and A.3: every "X{i}, Y{j}" cell of the
// markdown tables above each "TABLE A.n" caption, keyed "X{i}Y{j}".
inline std::map<std::string, SeedPoint> SeedCrossTable(const std::string& table /* "A.1" or "A.3" */) {
  std::map<std::string, SeedPoint> points;
  std::vector<std::string> pending;  // table rows since the last caption
  for (const std::string& line : SplitLines(ReadSeed("004_02f421a20419daf1.txt"))) {
    std::smatch caption;
    if (std::regex_search(line, caption, std::regex(R"(^\s*TABLE (A\.\d+))"))) {
      if (caption[1] == table) {
        for (const std::string& row : pending) {
          std::vector<std::string> cells;
          std::stringstream stream(row);
          std::string cell;
          std::getline(stream, cell, '|');  // before the first '|'
          while (std::getline(stream, cell, '|')) cells.push_back(cell);
          for (size_t k = 0; k + 2 < cells.size(); ++k) {
            std::smatch id;
            const std::string trimmed = Squeeze(cells[k]);
            if (!std::regex_match(trimmed, id, std::regex(R"(X(\d+)Y(\d+))"))) continue;
            points["X" + id[1].str() + "Y" + id[2].str()] = {std::stod(Squeeze(cells[k + 1])),
                                                             std::stod(Squeeze(cells[k + 2]))};
          }
        }
      }
      pending.clear();
      continue;
    }
    if (!line.empty() && line[0] == '|') pending.push_back(line);
  }
  return points;
}

// Seed 004 Table A.2: the fiducials "$A_x = -60.614$" ..., keyed by name (A, A', ...).
inline std::map<std::string, SeedPoint> SeedFiducialTable() {
  std::map<std::string, SeedPoint> points;
  const std::string text = ReadSeed("004_02f421a20419daf1.txt");
  const size_t begin = text.find("MASTER FIDUCIAL COORDINATE LIST");
  const size_t end = text.find("TABLE A.2", begin);
  if (begin == std::string::npos || end == std::string::npos) return points;
  const std::string section = text.substr(begin, end - begin);
  const std::regex value(R"(\$([A-Z])('?)_([xy]) = ([+-]?\s*[0-9.]+)\$)");
  for (auto it = std::sregex_iterator(section.begin(), section.end(), value); it != std::sregex_iterator(); ++it) {
    SeedPoint& point = points[(*it)[1].str() + (*it)[2].str()];
    ((*it)[3] == "x" ? point.x_mm : point.y_mm) = std::stod(Squeeze((*it)[4]));
  }
  return points;
}

// Seed 004 Table A.4 or A.5 (`caption` "TABLE A.4"): symbol (FL, X_p, K_1, \theta_0, ...)
// -> {value, S.D.}, with the OCR's " ^{-05}" read as e-05.
inline std::map<std::string, std::pair<double, double>> SeedLensTable(const std::string& caption) {
  std::map<std::string, std::pair<double, double>> values;
  const std::string text = ReadSeed("004_02f421a20419daf1.txt");
  const size_t end = text.find(caption);
  const size_t begin = text.rfind("CONSTANTS OF INTERNAL GEOMETRY", end);
  if (begin == std::string::npos || end == std::string::npos) return values;
  const std::string section = text.substr(begin, end - begin);
  const std::regex symbol(R"(^\$\$([A-Za-z_\\0-9]+) = )");
  const std::regex number(R"(= ([+-]?[0-9.]+) \\text\{ (?:\}\^\{([+-]?[0-9]+)\}|mm\}|radians\}))");
  for (const std::string& line : SplitLines(section)) {
    std::smatch name;
    if (!std::regex_search(line, name, symbol)) continue;
    std::vector<double> found;
    for (auto it = std::sregex_iterator(line.begin(), line.end(), number); it != std::sregex_iterator(); ++it) {
      std::string literal = (*it)[1].str();
      if ((*it)[2].matched) literal += "e" + (*it)[2].str();
      found.push_back(std::stod(literal));
    }
    if (found.size() == 2) values[name[1].str()] = {found[0], found[1]};
  }
  return values;
}

}  // namespace platemeter::testing
