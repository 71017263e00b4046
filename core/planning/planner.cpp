#include "core/planning/planner.hpp"

#include "core/common/error.hpp"
#include "core/common/strings.hpp"
#include "core/coverage/coverage_entry.hpp"
#include "core/team/team_entry.hpp"

namespace rover {

bool Planner::hasParam(const std::string& key) const {
  for (const auto& info : params())
    if (info.key == key) return true;
  return false;
}

void PlannerRegistry::add(std::unique_ptr<Planner> planner) {
  for (const auto& p : planners_)
    if (p->name() == planner->name())
      throw Error(ErrorCode::InvalidInput, "planner",
                  "planner '" + p->name() + "' registered twice");
  planners_.push_back(std::move(planner));
}

const Planner* PlannerRegistry::find(const std::string& name) const {
  for (const auto& p : planners_)
    if (p->name() == name) return p.get();
  return nullptr;
}

const Planner& PlannerRegistry::get(const std::string& name) const {
  if (const Planner* p = find(name)) return *p;
  std::string known = join(names(), ", ");
  throw Error(ErrorCode::NotFound, "planner",
              "unknown planner '" + name + "' (known: " + known + ")");
}

std::vector<std::string> PlannerRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& p : planners_) out.push_back(p->name());
  return out;
}

PlannerRegistry makeBuiltinRegistry() {
  PlannerRegistry r;
  r.add(coverage::makeCoveragePlanner());
  r.add(team::makeTeamSearchPlanner());
  r.add(team::makeHybridPlanner());
  return r;
}

}  // namespace rover
