#pragma once
// The TOML reading helper of the simulator's spec files (spec.cpp) and block
// specs (block_spec.cpp): typed getters with ranges, every problem an Error
// "<file>: line N: <table>: <problem>", unknown keys refused by Finish().
// Internal to samples/src; toml++ stays out of the public headers.
#include <cmath>
#include <cstdint>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "platemeter/core/error.h"

namespace platemeter::sim::spec_toml {

inline int LineOf(const toml::node& node) { return static_cast<int>(node.source().begin.line); }

class Table {
 public:
  Table(const toml::table& table, const std::string& origin, std::string what)
      : table_(table), origin_(origin), what_(std::move(what)) {}

  [[noreturn]] void Fail(int line, const std::string& problem) const {
    std::string reason = line > 0 ? "line " + std::to_string(line) + ": " : std::string();
    if (!what_.empty()) reason += what_ + ": ";
    throw Error(origin_, reason + problem);
  }
  [[noreturn]] void Fail(const toml::node* node, const std::string& problem) const {
    Fail(node ? LineOf(*node) : LineOf(table_), problem);
  }

  const toml::node* Get(const std::string& key) {
    used_.insert(key);
    return table_.get(key);
  }

  std::string String(const std::string& key, const std::string& fallback) {
    const toml::node* node = Get(key);
    if (!node) return fallback;
    if (!node->is_string()) Fail(node, "key '" + key + "' must be a string");
    return node->as_string()->get();
  }
  std::string RequireString(const std::string& key) {
    if (!table_.contains(key)) Fail(LineOf(table_), "missing required key '" + key + "' (a string)");
    return String(key, "");
  }
  double AsNumber(const toml::node* node, const std::string& key) const {
    double value = 0;
    if (node->is_integer()) {
      value = static_cast<double>(node->as_integer()->get());
    } else if (node->is_floating_point()) {
      value = node->as_floating_point()->get();
    } else {
      Fail(node, "key '" + key + "' must be a number");
    }
    if (!std::isfinite(value)) Fail(node, "key '" + key + "' must be finite");
    return value;
  }
  std::optional<double> OptionalNumber(const std::string& key, double min, double max) {
    const toml::node* node = Get(key);
    if (!node) return std::nullopt;
    const double value = AsNumber(node, key);
    if (value < min || value > max) {
      std::ostringstream range;
      range << "key '" << key << "' = " << value << " must lie in " << min << ".." << max;
      Fail(node, range.str());
    }
    return value;
  }
  void Number(const std::string& key, double* value, double min, double max) {
    if (auto v = OptionalNumber(key, min, max)) *value = *v;
  }
  void Integer(const std::string& key, int* value, int min, int max) {
    const toml::node* node = Get(key);
    if (!node) return;
    if (!node->is_integer()) Fail(node, "key '" + key + "' must be an integer");
    const int64_t v = node->as_integer()->get();
    if (v < min || v > max) {
      Fail(node, "key '" + key + "' = " + std::to_string(v) + " must lie in " + std::to_string(min) + ".." +
                     std::to_string(max));
    }
    *value = static_cast<int>(v);
  }
  void Bool(const std::string& key, bool* value) {
    const toml::node* node = Get(key);
    if (!node) return;
    if (!node->is_boolean()) Fail(node, "key '" + key + "' must be true or false");
    *value = node->as_boolean()->get();
  }
  // "dark" / "bright" -> dark.
  void Polarity(const std::string& key, bool* dark) {
    const toml::node* node = Get(key);
    if (!node) return;
    const std::string value = node->is_string() ? node->as_string()->get() : std::string();
    if (value != "dark" && value != "bright") Fail(node, "key '" + key + "' must be \"dark\" or \"bright\"");
    *dark = value == "dark";
  }
  // An array of exactly n numbers.
  void Numbers(const std::string& key, double* values, size_t n, double min, double max) {
    const toml::node* node = Get(key);
    if (!node) return;
    const toml::array* array = node->as_array();
    if (!array || array->size() != n) Fail(node, "key '" + key + "' must be an array of " + std::to_string(n) + " numbers");
    for (size_t i = 0; i < n; ++i) {
      const double v = AsNumber(array->get(i), key);
      if (v < min || v > max) {
        std::ostringstream range;
        range << "key '" << key << "' values must lie in " << min << ".." << max;
        Fail(node, range.str());
      }
      values[i] = v;
    }
  }
  std::vector<std::string> Strings(const std::string& key) {
    std::vector<std::string> out;
    const toml::node* node = Get(key);
    if (!node) return out;
    const toml::array* array = node->as_array();
    if (!array) Fail(node, "key '" + key + "' must be an array of strings");
    for (const toml::node& item : *array) {
      if (!item.is_string()) Fail(&item, "key '" + key + "' must be an array of strings");
      out.push_back(item.as_string()->get());
    }
    return out;
  }
  // Sub-tables, or an array of tables.
  const toml::table* SubTable(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) return nullptr;
    if (!node->is_table()) Fail(node, "'" + key + "' must be a table");
    return node->as_table();
  }
  std::vector<const toml::table*> TableArray(const std::string& key) {
    std::vector<const toml::table*> out;
    const toml::node* node = Get(key);
    if (!node) return out;
    const toml::array* array = node->as_array();
    if (!array) Fail(node, "'" + key + "' must be an array of tables ([[" + what_ + "." + key + "]])");
    for (const toml::node& item : *array) {
      if (!item.is_table()) Fail(&item, "'" + key + "' must be an array of tables");
      out.push_back(item.as_table());
    }
    return out;
  }
  // Unknown keys are errors (typos).
  void Finish() const {
    for (const auto& [key, node] : table_) {
      if (!used_.count(std::string(key.str()))) Fail(&node, "unknown key '" + std::string(key.str()) + "'");
    }
  }

 private:
  const toml::table& table_;
  const std::string& origin_;
  std::string what_;
  std::set<std::string> used_;
};

}  // namespace platemeter::sim::spec_toml
