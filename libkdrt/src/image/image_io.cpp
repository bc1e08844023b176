#include "common/atomic_file.h"
#include "common/read_input_file.h"
#include "image/netpbm.h"
#include "image/oiio_plugin.h"
#include "image/png_codec.h"

#include <kdrt/error.h>
#include <kdrt/image.h>

#include <algorithm>
#include <cmath>

namespace kdrt {

unsigned char to_8bit(float c) {
    float v = std::clamp(std::isnan(c) ? 0.0f : c, 0.0f, 1.0f);
    // std::lround without the libm call (a third of a PNG write's time): the
    // float product plus 0.5 is exact in double, and truncating a positive
    // number floors it, so halves round up as lround's do.
    return static_cast<unsigned char>(static_cast<double>(255.0f * v) + 0.5);
}

unsigned char to_8bit_srgb(float c) {
    const double v = std::clamp(std::isnan(c) ? 0.0 : static_cast<double>(c), 0.0, 1.0);
    const double encoded = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
    return static_cast<unsigned char>(std::lround(255.0 * encoded));
}

namespace {

std::string lower_extension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
    return ext;
}

bool is_tiff(const std::string& ext) { return ext == ".tif" || ext == ".tiff"; }

// Formats kdrt writes and reads itself; the rest go through OpenImageIO.
bool is_own_format(const std::string& ext) { return ext == ".png" || ext == ".ppm" || ext == ".pfm"; }

void check_image(const std::filesystem::path& path, const Image& image) {
    if (image.width <= 0 || image.height <= 0 ||
        image.rgb.size() / 3 / static_cast<std::size_t>(image.width) != static_cast<std::size_t>(image.height) ||
        image.rgb.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 3)
        throw Error(ErrorCode::InvalidArgument, path.string() + ": cannot write a " + std::to_string(image.width) + "x" +
                                                    std::to_string(image.height) + " image holding " +
                                                    std::to_string(image.rgb.size()) + " values (expected width * height * 3)");
}

void append_text(void* context, const char* text) { *static_cast<std::string*>(context) += text; }

void write_with_plugin(const std::filesystem::path& path, const std::string& ext, const Image& image, bool as_float,
                       const std::vector<unsigned char>& bytes) {
    const KdrtOiioPlugin& oiio = detail::oiio_plugin(path.string() + ": writing " + ext + " images");
    // The file is replaced only when complete (detail::AtomicFile): encoded in
    // memory and written, or written by OpenImageIO to a temporary file with
    // the target's extension and checked by reading it back.
    detail::AtomicFile file(path, ext);
    std::string error;
    const int result = oiio.write(
        path.c_str(), file.temporary().c_str(), image.width, image.height, as_float ? 1 : 0,
        as_float ? static_cast<const void*>(image.rgb.data()) : bytes.data(),
        [](void* f, const void* data, size_t size) { static_cast<detail::AtomicFile*>(f)->write(data, size); }, &file,
        append_text, &error);
    switch (result) {
    case KDRT_OIIO_ENCODED:
    case KDRT_OIIO_WROTE_FILE:
        break;
    case KDRT_OIIO_WRITE_FAILED:
        throw Error(ErrorCode::Io, path.string() + ": write failed: " + error + " (the previous file, if any, is unchanged)");
    case KDRT_OIIO_NO_READ_BACK:
        throw Error(ErrorCode::Io, path.string() + ": write failed: the written file does not read back"
                                                   " (disk full?); the previous file, if any, is unchanged");
    default:
        throw Error(ErrorCode::Io, path.string() + ": cannot encode the image: " + error);
    }
    file.commit();
}

}  // namespace

bool image_stores_floats(const std::filesystem::path& path, const ImageWriteOptions& options) {
    const std::string ext = lower_extension(path);
    return ext == ".exr" || ext == ".hdr" || ext == ".pfm" || (is_tiff(ext) && options.float_samples);
}

void write_image(const std::filesystem::path& path, const Image& image, const ImageWriteOptions& options) {
    check_image(path, image);
    const std::string ext = lower_extension(path);
    if (options.float_samples && !is_tiff(ext))
        throw Error(ErrorCode::InvalidArgument,
                    path.string() + ": float samples are an option of TIFF files only (exr, hdr and pfm are always float)");
    const bool as_float = image_stores_floats(path, options);
    std::vector<unsigned char> bytes;
    if (!as_float) {
        bytes.resize(image.rgb.size());
        if (options.encoding == Encoding::Srgb)
            std::transform(image.rgb.begin(), image.rgb.end(), bytes.begin(), to_8bit_srgb);
        else  // a lambda, so that to_8bit is inlined into the loop
            std::transform(image.rgb.begin(), image.rgb.end(), bytes.begin(), [](float c) { return to_8bit(c); });
    }
    std::vector<unsigned char> encoded;
    if (ext == ".png")
        encoded = detail::encode_png(bytes.data(), image.width, image.height, options.encoding == Encoding::Srgb);
    else if (ext == ".ppm")
        encoded = detail::encode_ppm(bytes.data(), image.width, image.height);
    else if (ext == ".pfm")
        encoded = detail::encode_pfm(image.rgb.data(), image.width, image.height);
    else
        return write_with_plugin(path, ext, image, as_float, bytes);
    detail::write_file_atomically(path, encoded);
}

void check_image_output(const std::filesystem::path& path) {
    const std::string ext = lower_extension(path);
    if (!is_own_format(ext) &&
        !detail::oiio_plugin(path.string() + ": writing " + (ext.empty() ? "extension-less" : ext) + " images")
             .has_writer(path.c_str()))
        throw Error(ErrorCode::Io, path.string() + ": no image writer for extension '" + path.extension().string() +
                                       "' (use png, exr, tif, ppm, pfm, ...)");
    detail::check_output_target(path);
}

Image read_image(const std::filesystem::path& path) {
    const std::string ext = lower_extension(path);
    if (is_own_format(ext)) {
        const std::string bytes = detail::read_input_file(path, "image file");
        return ext == ".png" ? detail::decode_png(bytes, path.string()) : detail::decode_netpbm(bytes, path.string());
    }
    const KdrtOiioPlugin& oiio = detail::oiio_plugin(path.string() + ": reading " + ext + " images");
    struct Buffer {
        int width = 0, height = 0, channels = 0;
        std::vector<float> pixels;
    } buffer;
    std::string error;
    const int ok = oiio.read(
        path.c_str(),
        [](void* b, int w, int h, int c) -> float* {
            auto* buf = static_cast<Buffer*>(b);
            if (w <= 0 || h <= 0 || c <= 0 || w > (1 << 20) || h > (1 << 20) || c > 64) return nullptr;
            *buf = {w, h, c, std::vector<float>(static_cast<std::size_t>(w) * h * c)};
            return buf->pixels.data();
        },
        &buffer, append_text, &error);
    if (!ok) throw Error(ErrorCode::Io, path.string() + ": cannot read image: " + error);
    Image image(buffer.width, buffer.height);
    for (std::size_t p = 0; p < static_cast<std::size_t>(buffer.width) * buffer.height; ++p)
        for (int c = 0; c < 3; ++c)
            image.rgb[p * 3 + c] = buffer.pixels[p * buffer.channels + std::min(c, buffer.channels - 1)];
    return image;
}

double image_rmse(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height)
        throw Error(ErrorCode::InvalidArgument, "image_rmse: images differ in size");
    double sum = 0.0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i) {
        double d = static_cast<double>(a.rgb[i]) - b.rgb[i];
        sum += d * d;
    }
    return a.rgb.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(a.rgb.size()));
}

double image_max_error(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height)
        throw Error(ErrorCode::InvalidArgument, "image_max_error: images differ in size");
    double m = 0.0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i)
        m = std::max(m, std::abs(static_cast<double>(a.rgb[i]) - b.rgb[i]));
    return m;
}

}  // namespace kdrt
