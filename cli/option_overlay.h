#pragma once
// Command-line options laid over a base request (a job file's, docs/job.md):
// only the options given explicitly on the command line replace its values.
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace platemeter::cli {

template <class Request>
class OptionOverlay {
 public:
  explicit OptionOverlay(CLI::App* cmd) : cmd_(cmd) {}
  OptionOverlay(const OptionOverlay&) = delete;  // CLI11 holds references into parsed_
  OptionOverlay& operator=(const OptionOverlay&) = delete;

  // An option read into field(parsed()); given, it replaces field(base).
  template <class Field>
  CLI::Option* Option(const std::string& name, Field field, const std::string& help) {
    return Bind(cmd_->add_option(name, field(parsed_), help), field);
  }
  template <class Field>
  CLI::Option* Flag(const std::string& name, Field field, const std::string& help) {
    return Bind(cmd_->add_flag(name, field(parsed_), help), field);
  }
  // Any other effect of a given option, applied in registration order.
  void OnGiven(CLI::Option* option, std::function<void(Request&)> apply) { rules_.emplace_back(option, std::move(apply)); }

  // base with every option given on the command line applied.
  Request Resolve(Request base) const {
    for (const auto& [option, apply] : rules_)
      if (option->count() > 0) apply(base);
    return base;
  }
  Request& parsed() { return parsed_; }
  CLI::App* command() const { return cmd_; }

 private:
  template <class Field>
  CLI::Option* Bind(CLI::Option* option, Field field) {
    OnGiven(option, [this, field](Request& base) { field(base) = field(parsed_); });
    return option;
  }

  CLI::App* cmd_;
  Request parsed_;
  std::vector<std::pair<CLI::Option*, std::function<void(Request&)>>> rules_;
};

}  // namespace platemeter::cli
