#include "geometry/io/png_io.h"

#include "geometry/error.h"
#include "geometry/atomic_file.h"

#include <png.h>

#include <cstring>

namespace vox {

// libpng's simplified API reports errors through png_image::message instead
// of longjmp, so no C++ frame is ever skipped.
static_assert(sizeof(Rgb) == 3, "RgbImage pixels are written as packed RGB rows");

namespace {
// Larger images are refused before allocating (a corrupt header must not
// trigger a multi-gigabyte allocation).
constexpr std::uint64_t kMaxPixels = std::uint64_t(1) << 28;
}  // namespace

void writePng(const std::string& path, const RgbImage& image) {
  if (image.width <= 0 || image.height <= 0 || image.pixels.size() != std::size_t(image.width) * std::size_t(image.height))
    throw RuntimeFailure(path + ": cannot write an empty or inconsistent image");
  png_image png;
  std::memset(&png, 0, sizeof(png));
  png.version = PNG_IMAGE_VERSION;
  png.width = png_uint_32(image.width);
  png.height = png_uint_32(image.height);
  png.format = PNG_FORMAT_RGB;
  AtomicFile file(path);
  std::FILE* f = file.openStdio();
  const int ok = png_image_write_to_stdio(&png, f, 0, image.pixels.data(), png_int_32(3 * image.width), nullptr);
  if (!ok) {
    const std::string message = png.message;
    png_image_free(&png);
    throw RuntimeFailure(path + ": PNG encoder failed: " + message);
  }
  file.commit();
}

RgbImage readPng(const std::string& path) {
  png_image png;
  std::memset(&png, 0, sizeof(png));
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str())) {
    const std::string message = png.message;
    png_image_free(&png);
    throw InputError(path, "not a readable PNG image (" + message + ")");
  }
  if (std::uint64_t(png.width) * std::uint64_t(png.height) > kMaxPixels) {
    png_image_free(&png);
    throw InputError(path, "PNG image of " + std::to_string(png.width) + " x " + std::to_string(png.height) + " pixels is too large");
  }
  png.format = PNG_FORMAT_RGB;
  RgbImage image(int(png.width), int(png.height));
  if (!png_image_finish_read(&png, nullptr, image.pixels.data(), png_int_32(3 * image.width), nullptr)) {
    const std::string message = png.message;
    png_image_free(&png);
    throw InputError(path, "corrupt PNG data (" + message + ")");
  }
  return image;
}

}  // namespace vox
