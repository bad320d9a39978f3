// Linear RGB float images (the fluence a method returns, the layers a scene reads) and 8-bit
// pictures.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace penumbra {

struct Rgb {
  float r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};

// Row-major, row 0 at the top (y down, the scene convention), 3 floats per pixel.
class ImageRgb {
 public:
  ImageRgb() = default;
  ImageRgb(int width, int height) : w_(width), h_(height), px_(std::size_t(width) * height * 3) {}
  // Takes over `pixels` (width * height * 3 floats) without copying.
  ImageRgb(int width, int height, std::vector<float>&& pixels)
      : w_(width), h_(height), px_(std::move(pixels)) {
    px_.resize(std::size_t(width) * height * 3);
  }

  int width() const { return w_; }
  int height() const { return h_; }
  float* data() { return px_.data(); }
  const float* data() const { return px_.data(); }
  std::size_t size() const { return px_.size(); }

  Rgb at(int x, int y) const {
    const float* p = &px_[(std::size_t(y) * w_ + x) * 3];
    return {p[0], p[1], p[2]};
  }
  void set(int x, int y, Rgb c) {
    float* p = &px_[(std::size_t(y) * w_ + x) * 3];
    p[0] = c.r;
    p[1] = c.g;
    p[2] = c.b;
  }

 private:
  int w_ = 0, h_ = 0;
  std::vector<float> px_;
};

// An 8-bit sRGB picture for people (a heatmap, a montage): row-major, row 0 at the top, 3 bytes
// per pixel.
struct ImageRgb8 {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;  // width * height * 3
};

}  // namespace penumbra
