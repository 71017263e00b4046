#pragma once
#include <charconv>
#include <cmath>
#include <string>
#include <vector>

namespace rover {

// "a|b|c" from {"a", "b", "c"} and "|".
inline std::string join(const std::vector<std::string>& items, const std::string& sep) {
  std::string out;
  for (const auto& s : items) {
    if (!out.empty()) out += sep;
    out += s;
  }
  return out;
}

// Text that reads back as exactly `v`: whole numbers below 1e15 as integers ("100000"), the rest
// in their shortest form ("0.1", "0.099999999", "1e+300"). Error messages quote a rejected value
// as the client sent it, not rounded to six digits.
inline std::string exactText(double v) {
  char buf[32];
  const auto r = std::abs(v) < 1e15 && std::trunc(v) == v
                     ? std::to_chars(buf, buf + sizeof buf, static_cast<long long>(v))
                     : std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

}  // namespace rover
