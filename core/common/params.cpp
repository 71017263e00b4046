#include "core/common/params.hpp"

#include <cmath>
#include <sstream>

#include "core/common/strings.hpp"

namespace rover {

const char* paramTypeName(ParamType type) {
  switch (type) {
    case ParamType::Bool:
      return "bool";
    case ParamType::Int:
      return "int";
    case ParamType::Real:
      return "real";
    case ParamType::Choice:
      return "choice";
    case ParamType::RealList:
      return "real_list";
  }
  return "?";
}

const char* paramLevelName(ParamLevel level) {
  return level == ParamLevel::Common ? "common" : "advanced";
}

ParamInfo common(ParamInfo info) {
  info.level = ParamLevel::Common;
  return info;
}

namespace {
// "must be in [min, max], got v" (appended piece by piece: GCC 12 reports a false -Wrestrict on
// chains of std::string operator+).
std::string outOfRange(const ParamInfo& info, const std::string& got) {
  std::string s = "must be in [";
  s.append(exactText(info.min)).append(", ").append(exactText(info.max)).append("], got ");
  s.append(got);
  return s;
}
}  // namespace

bool paramAsBool(const std::string& key, const ParamValue& v) {
  if (const bool* b = std::get_if<bool>(&v)) return *b;
  throwInvalidParameter(key, "expected true or false");
}

std::int64_t paramAsInt(const ParamInfo& info, const ParamValue& v) {
  std::int64_t i = 0;
  if (const auto* p = std::get_if<std::int64_t>(&v)) {
    i = *p;
  } else if (const auto* d = std::get_if<double>(&v);
             // Every whole double in (-2^63, 2^63) converts exactly: 9e18, inside the seed's
             // documented range, is a number a client may write as a float.
             d && std::isfinite(*d) && std::trunc(*d) == *d && std::fabs(*d) < 9.223372036854775808e18) {
    i = static_cast<std::int64_t>(*d);
  } else {
    throwInvalidParameter(info.key, "expected an integer");
  }
  if (static_cast<double>(i) < info.min || static_cast<double>(i) > info.max)
    throwInvalidParameter(info.key, outOfRange(info, std::to_string(i)));
  return i;
}

double paramAsReal(const ParamInfo& info, const ParamValue& v) {
  double d = 0;
  if (const auto* p = std::get_if<double>(&v)) {
    d = *p;
  } else if (const auto* i = std::get_if<std::int64_t>(&v)) {
    d = static_cast<double>(*i);
  } else {
    throwInvalidParameter(info.key, "expected a number");
  }
  if (!std::isfinite(d)) throwInvalidParameter(info.key, "must be a finite number");
  if (d < info.min || d > info.max)
    throwInvalidParameter(info.key, outOfRange(info, exactText(d)));
  return d;
}

std::string paramAsChoice(const ParamInfo& info, const ParamValue& v) {
  const auto* s = std::get_if<std::string>(&v);
  if (s) {
    for (const auto& c : info.choices)
      if (c == *s) return *s;
  }
  throwInvalidParameter(info.key, "must be one of " + join(info.choices, "|"));
}

std::vector<double> paramAsRealList(const std::string& key, const ParamValue& v) {
  const auto* l = std::get_if<std::vector<double>>(&v);
  if (!l) throwInvalidParameter(key, "expected a list of numbers");
  for (double d : *l)
    if (!std::isfinite(d)) throwInvalidParameter(key, "every value must be a finite number");
  return *l;
}

std::string paramToString(const ParamValue& v) {
  struct Visitor {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(std::int64_t i) const { return std::to_string(i); }
    std::string operator()(double d) const {
      std::ostringstream s;
      s << d;
      return s.str();
    }
    std::string operator()(const std::string& s) const { return s; }
    std::string operator()(const std::vector<double>& l) const {
      std::vector<std::string> items;
      for (double d : l) items.push_back((*this)(d));
      return join(items, ",");
    }
  };
  return std::visit(Visitor{}, v);
}

ParamInfo realParam(std::string key, double min, double max, std::string unit, std::string doc) {
  ParamInfo i;
  i.key = std::move(key);
  i.type = ParamType::Real;
  i.min = min;
  i.max = max;
  i.unit = std::move(unit);
  i.doc = std::move(doc);
  return i;
}

ParamInfo intParam(std::string key, double min, double max, std::string unit, std::string doc) {
  ParamInfo i = realParam(std::move(key), min, max, std::move(unit), std::move(doc));
  i.type = ParamType::Int;
  return i;
}

ParamInfo boolParam(std::string key, std::string doc) {
  ParamInfo i;
  i.key = std::move(key);
  i.type = ParamType::Bool;
  i.doc = std::move(doc);
  return i;
}

ParamInfo choiceParam(std::string key, std::vector<std::string> choices, std::string doc) {
  ParamInfo i;
  i.key = std::move(key);
  i.type = ParamType::Choice;
  i.choices = std::move(choices);
  i.doc = std::move(doc);
  return i;
}

}  // namespace rover
