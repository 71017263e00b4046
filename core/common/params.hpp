#pragma once
// Typed planner parameters described as data, so the CLI, the REST API and the web form can list
// every parameter with its default, unit and explanation, and reject unknown keys or bad values
// with the field's name. A planner keeps its own typed struct; a ParamTable<T> binds keys to its
// fields.
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "core/common/error.hpp"

namespace rover {

using ParamValue = std::variant<bool, std::int64_t, double, std::string, std::vector<double>>;
using ParamSet = std::map<std::string, ParamValue>;

enum class ParamType { Bool, Int, Real, Choice, RealList };
const char* paramTypeName(ParamType type);

// How prominent a parameter is in a form: the common ones shown first, the rest folded away.
enum class ParamLevel { Common, Advanced };
const char* paramLevelName(ParamLevel level);

struct ParamInfo {
  std::string key;
  ParamType type = ParamType::Real;
  ParamValue defaultValue;
  std::string unit;  // "" when dimensionless
  std::string doc;   // one sentence for the help text and the web form
  double min = -std::numeric_limits<double>::infinity();  // Int/Real inclusive range
  double max = std::numeric_limits<double>::infinity();
  std::vector<std::string> choices;  // Choice only
  std::string group;                 // the form's section ("route", "rrt", ...), set by the table
  ParamLevel level = ParamLevel::Advanced;
};

// A named set of values (e.g. "paper 001": the seed paper's study), checked against the table
// when it is added; keys not in it keep their defaults.
struct ParamPreset {
  std::string name;
  std::string doc;
  ParamSet values;
};

// Descriptions for ParamTable::add (the default is filled in from the struct).
ParamInfo realParam(std::string key, double min, double max, std::string unit, std::string doc);
ParamInfo intParam(std::string key, double min, double max, std::string unit, std::string doc);
ParamInfo boolParam(std::string key, std::string doc);
ParamInfo choiceParam(std::string key, std::vector<std::string> choices, std::string doc);
// Marks a description as one of the few a user sets most often (shown unfolded in forms).
ParamInfo common(ParamInfo info);

// Value coercions used by the tables; throw InvalidParameter naming `key`.
bool paramAsBool(const std::string& key, const ParamValue& v);
std::int64_t paramAsInt(const ParamInfo& info, const ParamValue& v);
double paramAsReal(const ParamInfo& info, const ParamValue& v);
std::string paramAsChoice(const ParamInfo& info, const ParamValue& v);
std::vector<double> paramAsRealList(const std::string& key, const ParamValue& v);
std::string paramToString(const ParamValue& v);

// Binds parameter keys to the fields of a typed struct P.
template <class P>
class ParamTable {
 public:
  using Setter = std::function<void(P&, const ParamInfo&, const ParamValue&)>;
  using Getter = std::function<ParamValue(const P&)>;

  // Every parameter added after this call belongs to the section `name`.
  void group(std::string name) { group_ = std::move(name); }
  void add(ParamInfo info, Getter get, Setter set) {
    info.defaultValue = get(P{});
    if (info.group.empty()) info.group = group_;
    entries_.push_back({std::move(info), std::move(get), std::move(set)});
  }
  // A preset is parsed once here, so a bad key or value in a table is caught at start-up.
  void preset(std::string name, std::string doc, ParamSet values) {
    parse(values);
    presets_.push_back({std::move(name), std::move(doc), std::move(values)});
  }
  const std::vector<ParamPreset>& presets() const { return presets_; }
  std::vector<ParamInfo> infos() const {
    std::vector<ParamInfo> out;
    for (const auto& e : entries_) out.push_back(e.info);
    return out;
  }
  // Defaults overridden by `values`; unknown keys and bad values throw with the key as field.
  P parse(const ParamSet& values) const {
    P p{};
    for (const auto& [key, value] : values) {
      const Entry* e = find(key);
      if (!e) throw Error(ErrorCode::UnknownParameter, key, "unknown parameter '" + key + "'");
      e->set(p, e->info, value);
    }
    return p;
  }
  ParamSet toSet(const P& p) const {
    ParamSet out;
    for (const auto& e : entries_) out[e.info.key] = e.get(p);
    return out;
  }

 private:
  struct Entry {
    ParamInfo info;
    Getter get;
    Setter set;
  };
  const Entry* find(const std::string& key) const {
    for (const auto& e : entries_)
      if (e.info.key == key) return &e;
    return nullptr;
  }
  std::vector<Entry> entries_;
  std::vector<ParamPreset> presets_;
  std::string group_ = "general";
};

}  // namespace rover
