// Linear RGB float images, written and read: PNG (libpng), PPM and PFM by
// kdrt itself; every other format through OpenImageIO, in a plugin loaded on
// first use (libkdrt_oiio.so, installed beside libkdrt).
#pragma once

#include <kdrt/export.h>

#include <glm/vec3.hpp>

#include <filesystem>
#include <vector>

namespace kdrt {

struct Image {
    int width = 0, height = 0;
    std::vector<float> rgb;  // width * height * 3, row-major from the top row

    Image() = default;
    Image(int w, int h) : width(w), height(h), rgb(static_cast<std::size_t>(w) * h * 3, 0.0f) {}
    glm::vec3 at(int x, int y) const {
        std::size_t i = (static_cast<std::size_t>(y) * width + x) * 3;
        return {rgb[i], rgb[i + 1], rgb[i + 2]};
    }
    void set(int x, int y, const glm::vec3& c) {
        std::size_t i = (static_cast<std::size_t>(y) * width + x) * 3;
        rgb[i] = c.x; rgb[i + 1] = c.y; rgb[i + 2] = c.z;
    }
};

// FORMAT.md's 8-bit rule: round(255 * clamp(c, 0, 1)), no transfer curve.
KDRT_API unsigned char to_8bit(float c);
// The sRGB alternative: round(255 * f(clamp(c, 0, 1))) with the IEC 61966-2-1
// transfer function f (12.92 c below 0.0031308, else 1.055 c^(1/2.4) - 0.055).
KDRT_API unsigned char to_8bit_srgb(float c);

// How values are stored in 8-bit formats.
enum class Encoding { Linear, Srgb };

struct ImageWriteOptions {
    Encoding encoding = Encoding::Linear;  // 8-bit formats only (PNG files get an sRGB chunk)
    bool float_samples = false;            // a TIFF with 32-bit float samples instead of 8-bit
};

// Whether `path` would hold float samples: exr, hdr and pfm always, tif/tiff
// with options.float_samples.
KDRT_API bool image_stores_floats(const std::filesystem::path& path, const ImageWriteOptions& options = {});

// Writes the image; the format follows the extension (png, exr, tif, ppm, pfm, ...).
// 8-bit formats store to_8bit(c) (to_8bit_srgb(c) with Encoding::Srgb); float
// formats store c. float_samples is refused (InvalidArgument) but for a TIFF.
// The file is replaced only once completely written (temporary file + rename);
// symlinks and special files at `path` are refused. Throws kdrt::Error(Io)
// naming the file and the OS error on failure (the previous file is then
// unchanged), kdrt::Error(InvalidArgument) when rgb does not hold
// width * height * 3 values.
KDRT_API void write_image(const std::filesystem::path& path, const Image& image, const ImageWriteOptions& options = {});

// Checks that `path` can be written as an image (a writer for its extension,
// a writable directory, no symlink or special file there) without writing it.
// Throws kdrt::Error(Io) otherwise. Formats beyond png, ppm and pfm load the
// OpenImageIO plugin, and fail naming it when it is not installed.
KDRT_API void check_image_output(const std::filesystem::path& path);

// Reads an image back as floats (8-bit files are divided by 255, no transfer
// curve is undone; grey is replicated, alpha dropped).
KDRT_API Image read_image(const std::filesystem::path& path);

// Root mean square error over all channels, and the largest channel difference.
KDRT_API double image_rmse(const Image& a, const Image& b);
KDRT_API double image_max_error(const Image& a, const Image& b);

}  // namespace kdrt
