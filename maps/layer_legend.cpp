#include "maps/layer_legend.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rover::maps {

namespace {

constexpr int kPad = 3;
constexpr Rgba kLegendBackground = {255, 255, 255, 255};

// "1234", "12.5", "0.125", "3.1e-5": short labels for the 5×7 font.
std::string formatValue(double v) {
  char buf[32];
  const double a = std::fabs(v);
  if (v == 0) return "0";
  if (a >= 1e-3 && a < 1e6) {
    const int decimals = a >= 100 ? 0 : a >= 10 ? 1 : a >= 1 ? 2 : 3;
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    std::string s = buf;
    if (s.find('.') != std::string::npos) {
      while (s.back() == '0') s.pop_back();
      if (s.back() == '.') s.pop_back();
    }
    return s == "-0" ? "0" : s;
  }
  std::snprintf(buf, sizeof buf, "%.1e", v);  // e.g. 3.1e-05 -> 3.1e-5
  std::string s = buf;
  const auto e = s.find('e');
  std::string mant = s.substr(0, e), exp = s.substr(e + 1);
  if (mant.size() > 2 && mant.compare(mant.size() - 2, 2, ".0") == 0) mant.resize(mant.size() - 2);
  const bool neg = exp[0] == '-';
  exp.erase(0, (exp[0] == '-' || exp[0] == '+') ? 1 : 0);
  while (exp.size() > 1 && exp[0] == '0') exp.erase(0, 1);
  return mant + "e" + (neg ? "-" : "") + exp;
}

}  // namespace

void drawRampLegend(Image& img, int y0, const RampLegend& lg) {
  Painter cv(img);
  cv.rect(0, y0, img.width, kRampLegendHeight, kLegendBackground);
  cv.text(lg.title, kPad, y0 + 3);
  const int barX = kPad, barW = img.width - 2 * kPad, barY = y0 + 12;
  for (int i = 0; i < barW; ++i) {
    const double v = lg.lo + (lg.hi - lg.lo) * (i + 0.5) / barW;
    cv.rect(barX + i, barY, 1, 8, lg.colour(v, lg));
  }
  // Ticks under the bar and their labels; a label that would overlap one already placed is
  // dropped (the end labels are placed first).
  std::vector<std::pair<int, int>> taken;
  auto place = [&](double v, int align) {  // align: -1 left, 0 centre, +1 right
    const int x = barX + static_cast<int>(std::lround((v - lg.lo) / (lg.hi - lg.lo) * (barW - 1)));
    const std::string s = formatValue(v);
    const int w = font::textWidth(s);
    int lx = align < 0 ? x : align > 0 ? x - w + 1 : x - w / 2;
    lx = std::clamp(lx, kPad, img.width - kPad - w);
    for (const auto& [a, b] : taken)
      if (lx < b + 4 && lx + w > a - 4) return;
    taken.emplace_back(lx, lx + w);
    cv.rect(x, barY + 8, 1, 2, kInk);
    cv.text(s, lx, y0 + 24);
  };
  place(lg.lo, -1);
  place(lg.hi, +1);
  for (double t : lg.ticks)
    if (t > lg.lo && t < lg.hi) place(t, 0);
}

int layoutClassLegend(int width, const std::vector<ClassItem>& items,
                      std::vector<std::pair<int, int>>* positions) {
  int x = kPad, y = 13;
  for (const auto& it : items) {
    const int w = 11 + font::textWidth(it.label);
    if (x > kPad && x + w > width - kPad) {
      x = kPad;
      y += 11;
    }
    if (positions) positions->emplace_back(x, y);
    x += w + 8;
  }
  return std::max(28, y + 8 + 4);
}

void drawClassLegend(Image& img, int y0, int height, const std::string& title,
                     const std::vector<ClassItem>& items) {
  Painter cv(img);
  cv.rect(0, y0, img.width, height, kLegendBackground);
  cv.text(title, kPad, y0 + 3);
  std::vector<std::pair<int, int>> pos;
  layoutClassLegend(img.width, items, &pos);
  for (std::size_t i = 0; i < items.size(); ++i) {
    const auto [x, y] = pos[i];
    cv.rect(x, y0 + y, 8, 8, kInk);
    cv.rect(x + 1, y0 + y + 1, 6, 6, kLegendBackground);  // a translucent colour shows as on paper
    cv.rect(x + 1, y0 + y + 1, 6, 6, items[i].colour);
    cv.text(items[i].label, x + 11, y0 + y + 1);
  }
}

}  // namespace rover::maps
