#include "core/coverage/cost_table.hpp"

#include <cmath>

#include "core/common/error.hpp"

namespace rover::coverage {

MotionCostTable spiralTable() {
  MotionCostTable t;
  //            straight L45   L90   L135  back  R135  R90   R45
  t.relative = {0.20, 0.40, 0.10, 0.70, 0.90, 0.80, 0.60, 0.50};
  return t;
}

MotionCostTable boustrophedonTable() {
  MotionCostTable t;
  // Small relative costs only break ties inside a lane change (left before right).
  t.relative = {0.00, 0.05, 0.10, 0.15, 0.20, 0.16, 0.11, 0.06};
  //            E     NE    N     NW    W     SW    S     SE
  t.absolute = {0.00, 0.60, 0.30, 0.60, 0.00, 0.70, 0.50, 0.70};
  return t;
}

void validateTable(const MotionCostTable& t, const std::string& field) {
  for (double v : t.relative)
    if (!std::isfinite(v) || v < 0) throwInvalidParameter(field, "costs must be finite and >= 0");
  for (double v : t.absolute)
    if (!std::isfinite(v) || v < 0) throwInvalidParameter(field, "costs must be finite and >= 0");
  for (int k = 1; k <= 3; ++k) {
    if (t.relative[k] == t.relative[8 - k])
      throwInvalidParameter(field, "left and right turns of " + std::to_string(45 * k) +
                                       "° must have different costs (paper 002 §2.1)");
  }
}

MotionCostTable tableFromList(const std::vector<double>& values, const std::string& field) {
  if (values.size() != 8 && values.size() != 16)
    throwInvalidParameter(field, "expected 8 relative costs, or 8 relative + 8 absolute");
  MotionCostTable t;
  for (int i = 0; i < 8; ++i) t.relative[i] = values[i];
  if (values.size() == 16)
    for (int i = 0; i < 8; ++i) t.absolute[i] = values[8 + i];
  validateTable(t, field);
  return t;
}

std::vector<double> tableToList(const MotionCostTable& t) {
  std::vector<double> out(t.relative.begin(), t.relative.end());
  out.insert(out.end(), t.absolute.begin(), t.absolute.end());
  return out;
}

}  // namespace rover::coverage
