#include "common/atomic_file.h"

#include <kdrt/error.h>
#include <kdrt/image.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace kdrt {

unsigned char to_8bit(float c) {
    float v = std::clamp(std::isnan(c) ? 0.0f : c, 0.0f, 1.0f);
    return static_cast<unsigned char>(std::lround(255.0f * v));
}

namespace {

std::string lower_extension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
    return ext;
}

bool is_float_format(const std::string& ext) {
    return ext == ".exr" || ext == ".hdr" || ext == ".pfm";
}

// The file at `path` decodes to a width x height image.
bool reads_back(const std::filesystem::path& path, int width, int height) {
    auto in = OIIO::ImageInput::open(path.string());
    if (!in) {
        OIIO::geterror();  // clear the thread's pending message
        return false;
    }
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width != width || spec.height != height || spec.nchannels < 1) return false;
    std::vector<float> pixels(static_cast<std::size_t>(width) * height * spec.nchannels);
    const bool ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data());
    if (!ok) in->geterror();
    return ok;
}

}  // namespace

void write_image(const std::filesystem::path& path, const Image& image) {
    if (image.width <= 0 || image.height <= 0 ||
        image.rgb.size() / 3 / static_cast<std::size_t>(image.width) != static_cast<std::size_t>(image.height) ||
        image.rgb.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 3)
        throw Error(ErrorCode::InvalidArgument, path.string() + ": cannot write a " + std::to_string(image.width) + "x" +
                                                    std::to_string(image.height) + " image holding " +
                                                    std::to_string(image.rgb.size()) + " values (expected width * height * 3)");
    const std::string ext = lower_extension(path);
    auto out = OIIO::ImageOutput::create(path.string());
    if (!out)
        throw Error(ErrorCode::Io, path.string() + ": no image writer for extension '" + ext + "' (" + OIIO::geterror() + ")");
    const bool as_float = is_float_format(ext);
    OIIO::ImageSpec spec(image.width, image.height, 3, as_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    std::vector<unsigned char> bytes;
    if (!as_float) {
        bytes.resize(image.rgb.size());
        std::transform(image.rgb.begin(), image.rgb.end(), bytes.begin(), to_8bit);
    }
    const void* pixels = as_float ? static_cast<const void*>(image.rgb.data()) : bytes.data();
    const OIIO::TypeDesc type = as_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8;

    // The file is replaced only when complete (detail::AtomicFile). Writers
    // that take an I/O proxy encode into memory first, so no codec ever sees
    // a disk error (libjpeg would exit() on one); the rest write a temporary
    // file with the target's extension, which is then renamed.
    detail::AtomicFile file(path, ext);
    if (out->supports("ioproxy")) {
        OIIO::Filesystem::IOVecOutput memory;
        if (!out->set_ioproxy(&memory) || !out->open(path.string(), spec) || !out->write_image(type, pixels) || !out->close())
            throw Error(ErrorCode::Io, path.string() + ": cannot encode the image: " + out->geterror());
        file.write(memory.buffer().data(), memory.buffer().size());
    } else {
        if (!out->open(file.temporary().string(), spec) || !out->write_image(type, pixels) || !out->close())
            throw Error(ErrorCode::Io, path.string() + ": write failed: " + out->geterror() +
                                           " (the previous file, if any, is unchanged)");
        // Some of these writers do not check their own writes (a full disk
        // passes as success): the file must read back whole before it counts.
        if (!reads_back(file.temporary(), image.width, image.height))
            throw Error(ErrorCode::Io, path.string() + ": write failed: the written file does not read back"
                                                       " (disk full?); the previous file, if any, is unchanged");
    }
    file.commit();
}

void check_image_output(const std::filesystem::path& path) {
    if (!OIIO::ImageOutput::create(path.string()))
        throw Error(ErrorCode::Io, path.string() + ": no image writer for extension '" + path.extension().string() +
                                       "' (use png, exr, tif, ppm, ...)");
    detail::check_output_target(path);
}

Image read_image(const std::filesystem::path& path) {
    auto in = OIIO::ImageInput::open(path.string());
    if (!in) throw Error(ErrorCode::Io, path.string() + ": cannot read image: " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
        throw Error(ErrorCode::Io, path.string() + ": cannot read image: " + in->geterror());
    Image image(spec.width, spec.height);
    for (std::size_t p = 0; p < static_cast<std::size_t>(spec.width) * spec.height; ++p)
        for (int c = 0; c < 3; ++c)
            image.rgb[p * 3 + c] = pixels[p * spec.nchannels + std::min(c, spec.nchannels - 1)];
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
