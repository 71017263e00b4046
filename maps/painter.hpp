#pragma once
// Painting on an RGBA image (maps::Image): alpha blending, clipped to the image, in pixel
// coordinates — the one painter of the layer legends (render.cpp) and the mission map
// (mission_map.cpp).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "maps/bitmap_font.hpp"
#include "maps/render.hpp"

namespace rover::maps {

struct Rgba {
  std::uint8_t r = 0, g = 0, b = 0, a = 255;  // opaque unless said
};
inline constexpr Rgba kTransparent{0, 0, 0, 0};
inline constexpr Rgba kInk{25, 25, 25, 255};  // legend and label text

class Painter {
 public:
  explicit Painter(Image& img) : img_(img) {}
  void blend(int x, int y, Rgba c) {
    if (x < 0 || y < 0 || x >= img_.width || y >= img_.height) return;
    std::uint8_t* p = &img_.rgba[(std::size_t(y) * img_.width + x) * 4];
    const int a = c.a;
    p[0] = static_cast<std::uint8_t>((c.r * a + p[0] * (255 - a)) / 255);
    p[1] = static_cast<std::uint8_t>((c.g * a + p[1] * (255 - a)) / 255);
    p[2] = static_cast<std::uint8_t>((c.b * a + p[2] * (255 - a)) / 255);
    p[3] = static_cast<std::uint8_t>(std::max<int>(p[3], a));
  }
  void rect(int x0, int y0, int w, int h, Rgba c) {
    for (int y = std::max(0, y0); y < std::min(img_.height, y0 + h); ++y)
      for (int x = std::max(0, x0); x < std::min(img_.width, x0 + w); ++x) blend(x, y, c);
  }
  void disc(double cx, double cy, double r, Rgba c) {
    for (int y = static_cast<int>(std::floor(cy - r)); y <= static_cast<int>(std::ceil(cy + r)); ++y)
      for (int x = static_cast<int>(std::floor(cx - r)); x <= static_cast<int>(std::ceil(cx + r)); ++x)
        if ((x + 0.5 - cx) * (x + 0.5 - cx) + (y + 0.5 - cy) * (y + 0.5 - cy) <= r * r) blend(x, y, c);
  }
  // A segment `width` pixels wide: discs along it, one a pixel (opaque colours only: a
  // translucent one would darken where the discs overlap).
  void line(double x0, double y0, double x1, double y1, double width, Rgba c) {
    const double len = std::hypot(x1 - x0, y1 - y0);
    const int n = std::max(1, static_cast<int>(std::ceil(len)));
    for (int i = 0; i <= n; ++i) disc(x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n, width / 2, c);
  }
  void text(const std::string& s, int x, int y, Rgba c = kInk) {
    font::drawText(s, x, y, [&](int px, int py) { blend(px, py, c); });
  }

 private:
  Image& img_;
};

}  // namespace rover::maps
