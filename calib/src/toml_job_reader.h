#pragma once
// Reading a job file (TOML) with messages that name the file and line: every
// key checked against its table's list, values checked against their ranges.
// Shared by the bundle and stellar job readers.
#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "platemeter/core/error.h"

namespace platemeter::job_toml {

inline int LineOf(const toml::node& node) { return static_cast<int>(node.source().begin.line); }

inline std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

class JobReader {
 public:
  // `doc` names the format's documentation in messages ("docs/bundle-job.md").
  JobReader(const std::string& path, std::string doc) : path_(path), doc_(std::move(doc)) {}

  [[noreturn]] void Fail(const toml::node* node, const std::string& problem) const {
    const int line = node ? LineOf(*node) : 0;
    throw Error(path_, (line > 0 ? "line " + std::to_string(line) + ": " : std::string()) + problem);
  }
  [[noreturn]] void FailKey(const toml::node& node, const std::string& key, const std::string& problem) const {
    Fail(&node, "key '" + key + "' " + problem);
  }

  // Every key of `table` must be in `allowed`.
  void CheckKeys(const toml::table& table, const std::string& prefix, const std::vector<std::string>& allowed) const {
    for (const auto& [name, node] : table) {
      const std::string key(name.str());
      bool known = false;
      for (const std::string& a : allowed) known = known || a == key;
      if (!known) {
        Fail(&node, "unknown key '" + prefix + key + "' (known: " + Join(allowed) + "; " + doc_ + ")");
      }
    }
  }

  std::string String(const toml::node& node, const std::string& key) const {
    if (!node.is_string()) FailKey(node, key, "must be a string");
    const std::string value = node.as_string()->get();
    if (value.empty()) FailKey(node, key, "must not be empty");
    return value;
  }
  double Number(const toml::node& node, const std::string& key, double min, double max,
                bool min_inclusive = true) const {
    double value = 0.0;
    if (node.is_integer()) {
      value = static_cast<double>(node.as_integer()->get());
    } else if (node.is_floating_point()) {
      value = node.as_floating_point()->get();
    } else {
      FailKey(node, key, "must be a number");
    }
    if (!std::isfinite(value) || value > max || (min_inclusive ? value < min : value <= min)) {
      std::ostringstream range;
      range << "= " << value << " must lie in " << (min_inclusive ? "[" : "(") << min << ", " << max << "]";
      FailKey(node, key, range.str());
    }
    return value;
  }
  long Integer(const toml::node& node, const std::string& key, long min, long max) const {
    if (!node.is_integer()) FailKey(node, key, "must be an integer");
    const long value = static_cast<long>(node.as_integer()->get());
    if (value < min || value > max) {
      FailKey(node, key, "= " + std::to_string(value) + " must lie in " + std::to_string(min) + ".." +
                             std::to_string(max));
    }
    return value;
  }
  bool Bool(const toml::node& node, const std::string& key) const {
    if (!node.is_boolean()) FailKey(node, key, "must be true or false");
    return node.as_boolean()->get();
  }
  // Each element in [min, max] (docs/bundle-job.md, "Accepted ranges").
  std::vector<double> Numbers(const toml::node& node, const std::string& key, size_t count, double min = -1e300,
                              double max = 1e300) const {
    const toml::array* array = node.as_array();
    if (!array || array->size() != count) {
      FailKey(node, key, "must be an array of " + std::to_string(count) + " numbers");
    }
    std::vector<double> out;
    for (const toml::node& item : *array) {
      if (!item.is_number()) FailKey(node, key, "must be an array of " + std::to_string(count) + " numbers");
      out.push_back(Number(item, key, min, max));
    }
    return out;
  }
  Eigen::Vector3d Vector3(const toml::node& node, const std::string& key, double min = -1e300,
                          double max = 1e300) const {
    const std::vector<double> v = Numbers(node, key, 3, min, max);
    return Eigen::Vector3d(v[0], v[1], v[2]);
  }
  Eigen::Matrix3d Matrix3(const toml::node& node, const std::string& key, double min = -1e300,
                          double max = 1e300) const {
    const toml::array* rows = node.as_array();
    if (!rows || rows->size() != 3) FailKey(node, key, "must be 3 rows of 3 numbers, [[..], [..], [..]]");
    Eigen::Matrix3d m;
    for (int r = 0; r < 3; ++r) m.row(r) = Vector3((*rows)[r], key, min, max).transpose();
    return m;
  }
  // A string or an array of strings.
  std::vector<std::pair<std::string, const toml::node*>> Strings(const toml::node& node, const std::string& key) const {
    std::vector<std::pair<std::string, const toml::node*>> out;
    if (node.is_string()) {
      out.emplace_back(String(node, key), &node);
      return out;
    }
    const toml::array* array = node.as_array();
    if (!array || array->empty()) FailKey(node, key, "must be a string or a non-empty array of strings");
    for (const toml::node& item : *array) {
      if (!item.is_string()) FailKey(node, key, "must be a string or a non-empty array of strings");
      out.emplace_back(String(item, key), &item);
    }
    return out;
  }
  // Relative to the job file's folder.
  std::string Path(const std::string& path) const {
    if (std::filesystem::path(path).is_absolute()) return path;
    return (std::filesystem::path(path_).parent_path() / path).lexically_normal().string();
  }
  // An array of tables ([[name]]); nullptr if absent.
  const toml::array* Tables(const toml::table& root, const char* name) const {
    const toml::node* node = root.get(name);
    if (!node) return nullptr;
    const toml::array* array = node->as_array();
    if (!array || !array->is_array_of_tables()) {
      Fail(node, "'" + std::string(name) + "' must be an array of tables, written [[" + name + "]]");
    }
    return array;
  }
  const toml::table* Table(const toml::table& root, const char* name) const {
    const toml::node* node = root.get(name);
    if (!node) return nullptr;
    if (!node->is_table()) Fail(node, "'" + std::string(name) + "' must be a table, written [" + name + "]");
    return node->as_table();
  }

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string doc_;
};

}  // namespace platemeter::job_toml
