#include "core/planning/plan_result.hpp"

#include "core/common/error.hpp"

namespace rover {

double PlanResult::metric(const std::string& key) const {
  for (const auto& m : metrics)
    if (m.key == key) return m.value;
  throw Error(ErrorCode::NotFound, key, "no metric '" + key + "' in the result");
}

}  // namespace rover
