#include "render/image_output.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <vector>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include "gwnrt/io/output_file.h"

namespace gwnrt::render {

namespace {

// The sRGB transfer function (IEC 61966-2-1): linear light in [0, 1] to the encoded value.
float srgb_encode(float linear) {
  const float c = std::clamp(linear, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

// Writes `bytes` to `path` whole or not at all (ReplacingFile: beside it, then renamed over it),
// checking the write, the flush and the close: a full disk is often reported only by the last two.
Status write_bytes(const std::string& path, const std::vector<unsigned char>& bytes) {
  ReplacingFile out(path);
  if (Status s = out.open(); !s.ok()) return s;
  errno = 0;
  const bool written = bytes.empty() || std::fwrite(bytes.data(), 1, bytes.size(), out.file()) == bytes.size();
  return out.commit(written ? 0 : (errno ? errno : EIO));
}

std::vector<uint8_t> encode_srgb8(const Image& image) {
  const int w = image.width(), h = image.height();
  std::vector<uint8_t> bytes(std::size_t(w) * std::size_t(h) * 3);
  // Every pixel goes through pow(): a 4096-entry table of the curve would do, but even the
  // largest renders spend far longer tracing than encoding.
  std::size_t k = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float* p = image.pixel(x, y);
      for (int c = 0; c < 3; ++c) bytes[k++] = uint8_t(std::lround(255.0f * srgb_encode(p[c])));
    }
  }
  return bytes;
}

}  // namespace

Status oiio_error(const std::string& path, const std::string& what, std::string message) {
  // OpenImageIO messages may end in a newline; the caller prints its own.
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
  if (message.empty()) message = "unknown OpenImageIO error";
  return {StatusCode::kIoError, path + ": " + what + ": " + message};
}

std::optional<ImageFormat> image_format_for(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".png") return ImageFormat::kPng;
  if (ext == ".exr") return ImageFormat::kExr;
  return std::nullopt;
}

const char* image_format_name(ImageFormat format) { return format == ImageFormat::kPng ? "PNG" : "EXR"; }

const char* supported_image_extensions() { return ".png, .exr"; }

Status write_image(const std::string& path, const Image& image, const std::string& description) {
  const std::optional<ImageFormat> format = image_format_for(path);
  if (!format) {
    return {StatusCode::kInvalidArgument,
            path + ": unknown image extension (supported: " + std::string(supported_image_extensions()) + ")"};
  }
  if (image.width() <= 0 || image.height() <= 0 || image.channels() < 3) {
    return {StatusCode::kInvalidArgument, path + ": nothing to write (empty image or fewer than three channels)"};
  }

  // Encoded into memory: OpenImageIO's writers do not all report a failed write or close (a PNG
  // to a full disk "succeeds"), so the bytes are written to the file below, every step checked.
  OIIO::Filesystem::IOVecOutput encoded;
  std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path, &encoded);
  if (!out) return oiio_error(path, "cannot create an image writer", OIIO::geterror());
  if (!out->supports("ioproxy")) return {StatusCode::kInternal, path + ": the image writer cannot encode into memory"};

  const bool png = *format == ImageFormat::kPng;
  const int channels = png ? 3 : image.channels();
  OIIO::ImageSpec spec(image.width(), image.height(), channels, png ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT);
  spec.channelnames.assign(image.channel_names().begin(), image.channel_names().begin() + channels);
  // The constructor guesses that a fourth channel is alpha; ours are named, so say which (if any).
  const auto alpha = std::find(spec.channelnames.begin(), spec.channelnames.end(), "A");
  spec.alpha_channel = alpha == spec.channelnames.end() ? -1 : int(alpha - spec.channelnames.begin());
  spec.attribute("oiio:ColorSpace", png ? "sRGB" : "Linear");
  spec.attribute("Software", "gwnrt-render");
  if (!description.empty()) spec.attribute("ImageDescription", description);
  if (!png) spec.attribute("compression", "zip");

  if (!out->open(path, spec)) return oiio_error(path, "cannot open for writing", out->geterror());
  bool written;
  if (png) {
    const std::vector<uint8_t> bytes = encode_srgb8(image);
    written = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
  } else {
    written = out->write_image(OIIO::TypeDesc::FLOAT, image.data().data());
  }
  if (!written) {
    Status s = oiio_error(path, "write failed", out->geterror());
    out->close();
    return s;
  }
  if (!out->close()) return oiio_error(path, "write failed", out->geterror());
  out.reset();
  return write_bytes(path, encoded.buffer());
}

uint64_t write_image_bytes_per_pixel(ImageFormat format, int channels) {
  // PNG: the 8-bit RGB copy and its encoding; EXR: its (compressed) encoding of the floats.
  return format == ImageFormat::kPng ? 3 + 3 : 4 * uint64_t(channels);
}

std::optional<std::string> check_writable(const std::string& path) {
  // O_EXCL: a file made here is known to be ours, and is removed again; an existing one is
  // opened without truncating it, so that nothing in it changes.
  int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd >= 0) {
    ::close(fd);
    ::unlink(path.c_str());
    return std::nullopt;
  }
  if (errno == EEXIST) fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd >= 0) {
    ::close(fd);
    return std::nullopt;
  }
  return path + ": cannot be written: " + std::strerror(errno);
}

Image tone_mapped(const Image& image) {
  Image out(image.width(), image.height(), {"R", "G", "B"});
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      const float* p = image.pixel(x, y);
      float* q = out.pixel(x, y);
      for (int c = 0; c < 3; ++c) {
        const float v = p[c] > 0.0f ? p[c] : 0.0f;
        if (v <= 1.0f) {
          q[c] = (v * (2.51f * v + 0.03f)) / (v * (2.43f * v + 0.59f) + 0.14f);
        } else {
          // The same curve divided through by v², so that v² cannot overflow (from v = 1.8e19,
          // inf / inf would make a bright pixel black).
          const float r = 1.0f / v;
          q[c] = (2.51f + 0.03f * r) / (2.43f + (0.59f + 0.14f * r) * r);
        }
      }
    }
  return out;
}

}  // namespace gwnrt::render
