#include "server/cli/arg_parser.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace rover::cli {

ArgParser::ArgParser(std::string command, std::string summary)
    : command_(std::move(command)), summary_(std::move(summary)) {}

void ArgParser::option(const std::string& name, const std::string& valueName,
                       const std::string& defaultText, const std::string& help) {
  specs_.push_back({name, valueName, defaultText, help, false});
}

void ArgParser::flag(const std::string& name, const std::string& help) {
  specs_.push_back({name, "", "", help, true});
}

void ArgParser::positional(const std::string& name, const std::string& help) {
  positionalSpecs_.emplace_back(name, help);
}

const ArgParser::Spec* ArgParser::find(const std::string& name) const {
  for (const auto& s : specs_)
    if (s.name == name) return &s;
  return nullptr;
}

bool ArgParser::parse(const std::vector<std::string>& args) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") return false;
    if (a.rfind("--", 0) != 0) {
      if (positionalValues_.size() >= positionalSpecs_.size())
        throw UsageError("unexpected argument '" + a + "'");
      positionalValues_.push_back(a);
      continue;
    }
    std::string name = a.substr(2), value;
    bool inlineValue = false;
    if (auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
      inlineValue = true;
    }
    const Spec* spec = find(name);
    if (!spec) throw UsageError("unknown option --" + name + " (see --help)");
    if (spec->isFlag) {
      if (inlineValue) throw UsageError("option --" + name + " takes no value");
      values_[name] = "true";
      continue;
    }
    if (!inlineValue) {
      if (i + 1 >= args.size()) throw UsageError("option --" + name + " needs a value");
      value = args[++i];
    }
    values_[name] = value;
  }
  if (positionalValues_.size() < positionalSpecs_.size())
    throw UsageError("missing argument " + positionalSpecs_[positionalValues_.size()].first);
  return true;
}

std::string ArgParser::help() const {
  std::ostringstream out;
  out << "usage: roverplan " << command_;
  for (const auto& [name, help] : positionalSpecs_) out << " " << name;
  out << " [options]\n" << summary_ << "\n";
  if (!positionalSpecs_.empty()) {
    out << "\narguments:\n";
    for (const auto& [name, help] : positionalSpecs_)
      out << "  " << name << "\n      " << help << "\n";
  }
  out << "\noptions:\n";
  for (const auto& s : specs_) {
    out << "  --" << s.name;
    if (!s.isFlag) out << " " << s.valueName;
    out << "\n      " << s.help;
    if (!s.defaultText.empty()) out << " (default: " << s.defaultText << ")";
    out << "\n";
  }
  out << "  --help\n      Show this help.\n";
  return out.str();
}

std::string ArgParser::str(const std::string& name, const std::string& fallback) const {
  auto it = values_.find(name);
  return it == values_.end() ? fallback : it->second;
}

long long ArgParser::integer(const std::string& name, long long fallback, long long min,
                             long long max) const {
  auto it = values_.find(name);
  if (it == values_.end()) return fallback;
  const std::string& s = it->second;
  char* end = nullptr;
  errno = 0;
  long long v = std::strtoll(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || errno == ERANGE)
    throw UsageError("invalid value '" + s + "' for --" + name + ": expected an integer");
  if (v < min || v > max)
    throw UsageError("invalid value '" + s + "' for --" + name + ": must be in [" +
                     std::to_string(min) + ", " + std::to_string(max) + "]");
  return v;
}

double ArgParser::real(const std::string& name, double fallback, double min, double max) const {
  auto it = values_.find(name);
  if (it == values_.end()) return fallback;
  const std::string& s = it->second;
  char* end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !std::isfinite(v))
    throw UsageError("invalid value '" + s + "' for --" + name + ": expected a number");
  if (v < min || v > max) {
    std::ostringstream m;
    m << "invalid value '" << s << "' for --" << name << ": must be in [" << min << ", " << max
      << "]";
    throw UsageError(m.str());
  }
  return v;
}

std::vector<double> ArgParser::realList(const std::string& name) const {
  std::vector<double> out;
  auto it = values_.find(name);
  if (it == values_.end()) return out;
  if (!it->second.empty() && it->second.back() == ',')
    throw UsageError("invalid value '" + it->second + "' for --" + name +
                     ": expected comma-separated numbers");
  std::stringstream ss(it->second);
  for (std::string item; std::getline(ss, item, ',');) {
    char* end = nullptr;
    double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v))
      throw UsageError("invalid value '" + it->second + "' for --" + name +
                       ": expected comma-separated numbers");
    out.push_back(v);
  }
  return out;
}

}  // namespace rover::cli
