#pragma once
// Command-line options for roverplan's subcommands: `--name VALUE`, `--name=VALUE` and flags, a
// help text listing every option with its default, and a UsageError (exit status 2) that names the
// offending option.
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/common/error.hpp"

namespace rover::cli {

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Runs `fn`, turning a rover::Error it throws into a one-line usage error (exit status 2).
template <class Fn>
auto orUsage(Fn&& fn) {
  try {
    return fn();
  } catch (const Error& e) {
    throw UsageError(e.what());
  }
}

class ArgParser {
 public:
  ArgParser(std::string command, std::string summary);

  // An option taking a value; `defaultText` is shown in --help ("" = no default).
  void option(const std::string& name, const std::string& valueName, const std::string& defaultText,
              const std::string& help);
  void flag(const std::string& name, const std::string& help);
  // Positional arguments, in order (shown in the usage line).
  void positional(const std::string& name, const std::string& help);

  // Parses args (without the program and command names). Returns false when --help was given.
  bool parse(const std::vector<std::string>& args);
  std::string help() const;

  bool has(const std::string& name) const { return values_.count(name) > 0; }
  bool isSet(const std::string& flag) const { return has(flag); }
  std::string str(const std::string& name, const std::string& fallback) const;
  long long integer(const std::string& name, long long fallback, long long min,
                    long long max) const;
  double real(const std::string& name, double fallback, double min, double max) const;
  std::vector<double> realList(const std::string& name) const;
  const std::vector<std::string>& positionals() const { return positionalValues_; }

 private:
  struct Spec {
    std::string name, valueName, defaultText, help;
    bool isFlag = false;
  };
  const Spec* find(const std::string& name) const;
  std::string command_, summary_;
  std::vector<Spec> specs_;
  std::vector<std::pair<std::string, std::string>> positionalSpecs_;
  std::map<std::string, std::string> values_;
  std::vector<std::string> positionalValues_;
};

}  // namespace rover::cli
