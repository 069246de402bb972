#pragma once
// TableReader: reads the keys of one TOML table of a definition file
// (definition_reader.cpp), with errors "<file>: line N: <definition>: <problem>".
#include <cmath>
#include <optional>
#include <set>
#include <string>
#include <toml++/toml.h>

#include "platemeter/core/error.h"
#include "platemeter/core/text_input.h"

namespace platemeter::definition_toml {

inline int LineOf(const toml::node& node) { return static_cast<int>(node.source().begin.line); }

// Reads the keys of one TOML table and remembers which ones were used, so the
// rest can be reported as unknown.
class TableReader {
 public:
  TableReader(const toml::table& table, const std::string& origin, std::string what)
      : table_(table), origin_(origin), what_(std::move(what)) {}

  [[noreturn]] void Fail(int line, const std::string& problem) const {
    std::string reason;
    if (line > 0) reason = "line " + std::to_string(line) + ": ";
    if (!what_.empty()) reason += what_ + ": ";
    throw Error(origin_, reason + problem);
  }
  [[noreturn]] void Fail(const toml::node* node, const std::string& problem) const {
    Fail(node ? LineOf(*node) : LineOf(table_), problem);
  }

  void SetWhat(std::string what) { what_ = std::move(what); }
  int line() const { return LineOf(table_); }

  const toml::node* Get(const std::string& key) {
    used_.insert(key);
    return table_.get(key);
  }
  bool Has(const std::string& key) const { return table_.contains(key); }

  std::string RequireString(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) Fail(line(), "missing required key '" + key + "' (a string)");
    return AsString(node, key);
  }
  std::string OptionalString(const std::string& key) {
    const toml::node* node = Get(key);
    return node ? AsString(node, key) : std::string();
  }
  std::string AsString(const toml::node* node, const std::string& key) const {
    if (!node->is_string()) Fail(node, "key '" + key + "' must be a string");
    return node->as_string()->get();
  }

  double RequireNumber(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) Fail(line(), "missing required key '" + key + "' (a number)");
    return AsNumber(node, "key '" + key + "'");
  }
  std::optional<double> OptionalNumber(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) return std::nullopt;
    return AsNumber(node, "key '" + key + "'");
  }
  double RequireNumber(const std::string& key, const NumberRange& range) {
    return InRange(Get(key), "key '" + key + "'", RequireNumber(key), range);
  }
  std::optional<double> OptionalNumber(const std::string& key, const NumberRange& range) {
    const std::optional<double> value = OptionalNumber(key);
    if (value) InRange(Get(key), "key '" + key + "'", *value, range);
    return value;
  }
  double InRange(const toml::node* node, const std::string& name, double value, const NumberRange& range) const {
    if (!range.Contains(value)) {
      Fail(node, name + " = " + ShortNumber(value) + " is outside the accepted range " + range.Describe());
    }
    return value;
  }
  // Integers are accepted where a number is expected (x = 0 means 0.0).
  double AsNumber(const toml::node* node, const std::string& name) const {
    double value = 0.0;
    if (node->is_floating_point()) {
      value = node->as_floating_point()->get();
    } else if (node->is_integer()) {
      value = static_cast<double>(node->as_integer()->get());
    } else {
      Fail(node, name + " must be a number");
    }
    if (!std::isfinite(value)) Fail(node, name + " must be a finite number");
    return value;
  }

  int RequireCount(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) Fail(line(), "missing required key '" + key + "' (a positive integer)");
    if (!node->is_integer()) Fail(node, "key '" + key + "' must be an integer");
    const int64_t value = node->as_integer()->get();
    if (value < 1 || value > 100000) Fail(node, "key '" + key + "' must be between 1 and 100000");
    return static_cast<int>(value);
  }

  bool OptionalBool(const std::string& key, bool fallback) {
    const toml::node* node = Get(key);
    if (!node) return fallback;
    if (!node->is_boolean()) Fail(node, "key '" + key + "' must be true or false");
    return node->as_boolean()->get();
  }

  const toml::table* OptionalTable(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) return nullptr;
    if (!node->is_table()) Fail(node, "key '" + key + "' must be a table");
    return node->as_table();
  }
  const toml::table& RequireTable(const std::string& key) {
    if (!Has(key)) Fail(line(), "missing required table '" + key + "'");
    return *OptionalTable(key);
  }
  const toml::array* OptionalArray(const std::string& key) {
    const toml::node* node = Get(key);
    if (!node) return nullptr;
    if (!node->is_array()) Fail(node, "key '" + key + "' must be an array");
    return node->as_array();
  }

  void RejectUnknownKeys() const {
    for (auto&& [key, node] : table_) {
      const std::string name(key.str());
      if (used_.count(name)) continue;
      const int line = key.source().begin.line > 0 ? static_cast<int>(key.source().begin.line) : LineOf(node);
      Fail(line, "unknown key '" + name + "'");
    }
  }

  const std::string& origin() const { return origin_; }
  const std::string& what() const { return what_; }

 private:
  const toml::table& table_;
  const std::string& origin_;
  std::string what_;
  std::set<std::string> used_;
};

}  // namespace platemeter::definition_toml
