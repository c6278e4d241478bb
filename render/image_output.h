// Writing images to PNG (8-bit, sRGB-encoded) or OpenEXR (32-bit float, linear) through
// OpenImageIO. The OpenImageIO headers stay in image_output.cpp: this header is plain C++ so
// that code nvcc compiles (a future CUDA render path) can include it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "gwnrt/base/status.h"
#include "render/image.h"

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
// command line that made it, say). The file is encoded in memory and then written and closed
// here, so that every failure (a full disk, /dev/full) is reported: with
// OpenImageIO's own error message, or the system's.
Status write_image(const std::string& path, const Image& image, const std::string& description = {});

// The memory write_image needs per pixel beyond the image itself (PNG's 8-bit copy; the encoded
// file, at most about the size of its raw pixels), for checking a size before rendering it.
uint64_t write_image_bytes_per_pixel(ImageFormat format, int channels);

// An OpenImageIO failure as a Status: "path: what: message", the message's trailing newline
// dropped ("unknown OpenImageIO error" when it is empty).
Status oiio_error(const std::string& path, const std::string& what, std::string message);

// Why `path` cannot be written, or nothing: tried up front, before a long render, by opening it
// for writing (creating it, and removing it again, when it does not exist yet). Names the path
// and the system's reason (a missing or read-only directory, /proc, a directory at the path).
std::optional<std::string> check_writable(const std::string& path);

// A high-dynamic-range render made displayable: the first three channels through a filmic curve
// (Narkowicz's fit of the ACES response) that maps [0, ∞) onto [0, 1) and keeps mid-tones, for
// PNG; the other channels are dropped.
Image tone_mapped(const Image& image);

}  // namespace gwnrt::render
