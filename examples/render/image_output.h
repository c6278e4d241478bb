// Writing images to PNG (8-bit, sRGB-encoded) or OpenEXR (32-bit float, linear) through
// OpenImageIO. The OpenImageIO headers stay in image_output.cpp: this header is plain C++ so
// that code nvcc compiles (a future CUDA render path) can include it.
#pragma once

#include <optional>
#include <string>

#include "gwnrt/status.h"
#include "image.h"

namespace gwnrt::render {

enum class ImageFormat { kPng, kExr };

// The format named by the file's extension (case-insensitive), or nothing for any other.
std::optional<ImageFormat> image_format_for(const std::string& path);

// "PNG", "EXR": for messages.
const char* image_format_name(ImageFormat format);

// The extensions image_format_for accepts, for messages: ".png, .exr".
const char* supported_image_extensions();

// Writes `image` to `path` in the format its extension names. PNG keeps the first three
// channels (as R, G, B) and encodes them with the sRGB transfer curve; EXR keeps every channel,
// linear, under the image's channel names. `description` goes into the file's metadata (the
// command line that made it, say). Fails with OpenImageIO's own message.
Status write_image(const std::string& path, const Image& image, const std::string& description = {});

// A high-dynamic-range render made displayable: the first three channels through a filmic curve
// (Narkowicz's fit of the ACES response) that maps [0, ∞) onto [0, 1) and keeps mid-tones, for
// PNG; the other channels are dropped.
Image tone_mapped(const Image& image);

}  // namespace gwnrt::render
