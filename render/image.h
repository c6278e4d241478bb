// An image in memory: rows of interleaved float channels, linear light for colour channels
// (the writer encodes for the file format). Row 0 is the top row, as the camera numbers them.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "gwnrt/base/hd.h"

namespace gwnrt::render {

class Image {
 public:
  Image() = default;
  // `channel_names` gives the channel count; the first three are taken as R, G, B by formats
  // that hold only colour (PNG). Extra named channels (step counts, ...) reach EXR files as is.
  Image(int width, int height, std::vector<std::string> channel_names)
      : width_(width),
        height_(height),
        channel_names_(std::move(channel_names)),
        pixels_(std::size_t(width) * std::size_t(height) * channel_names_.size(), 0.0f) {}

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return int(channel_names_.size()); }
  const std::vector<std::string>& channel_names() const { return channel_names_; }

  float* pixel(int x, int y) { return pixels_.data() + offset(x, y); }
  const float* pixel(int x, int y) const { return pixels_.data() + offset(x, y); }
  void set_rgb(int x, int y, const vec3& c) {
    float* p = pixel(x, y);
    p[0] = c.x;
    p[1] = c.y;
    p[2] = c.z;
  }
  const std::vector<float>& data() const { return pixels_; }

 private:
  std::size_t offset(int x, int y) const {
    return (std::size_t(y) * std::size_t(width_) + std::size_t(x)) * channel_names_.size();
  }

  int width_ = 0, height_ = 0;
  std::vector<std::string> channel_names_;
  std::vector<float> pixels_;
};

}  // namespace gwnrt::render
