// libkdrt_oiio.so: the image formats libkdrt does not write itself, through
// OpenImageIO (plugin_abi.h says why this is a plugin). Loaded with dlopen by
// image/oiio_plugin.cpp.
#include "plugin_abi.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <string>
#include <vector>

namespace {

// The file at `path` decodes to a width x height image.
bool reads_back(const std::string& path, int width, int height) {
    auto in = OIIO::ImageInput::open(path);
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

int has_writer(const char* path) { return OIIO::ImageOutput::create(path) ? 1 : 0; }

int write(const char* format_path, const char* file, int width, int height, int is_float, const void* pixels,
          KdrtOiioSink sink, void* sink_context, KdrtOiioText error, void* error_context) {
    auto out = OIIO::ImageOutput::create(format_path);
    if (!out) {
        error(error_context, OIIO::geterror().c_str());
        return KDRT_OIIO_ENCODE_FAILED;
    }
    const OIIO::TypeDesc type = is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8;
    const OIIO::ImageSpec spec(width, height, 3, type);
    // Writers that take an I/O proxy encode into memory, so no codec ever
    // sees a disk error (libjpeg would exit() on one).
    if (out->supports("ioproxy")) {
        OIIO::Filesystem::IOVecOutput memory;
        if (!out->set_ioproxy(&memory) || !out->open(format_path, spec) || !out->write_image(type, pixels) ||
            !out->close()) {
            error(error_context, out->geterror().c_str());
            return KDRT_OIIO_ENCODE_FAILED;
        }
        sink(sink_context, memory.buffer().data(), memory.buffer().size());
        return KDRT_OIIO_ENCODED;
    }
    if (!out->open(file, spec) || !out->write_image(type, pixels) || !out->close()) {
        error(error_context, out->geterror().c_str());
        return KDRT_OIIO_WRITE_FAILED;
    }
    // Some of these writers do not check their own writes (a full disk
    // passes as success): the file must read back whole before it counts.
    return reads_back(file, width, height) ? KDRT_OIIO_WROTE_FILE : KDRT_OIIO_NO_READ_BACK;
}

int read(const char* path, KdrtOiioPixels pixels, void* pixels_context, KdrtOiioText error, void* error_context) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        error(error_context, OIIO::geterror().c_str());
        return 0;
    }
    const OIIO::ImageSpec& spec = in->spec();
    float* buffer = pixels(pixels_context, spec.width, spec.height, spec.nchannels);
    if (!buffer) {
        error(error_context, "bad image size");
        return 0;
    }
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, buffer)) {
        error(error_context, in->geterror().c_str());
        return 0;
    }
    return 1;
}

const KdrtOiioPlugin plugin{KDRT_OIIO_ABI_VERSION, has_writer, write, read};

}  // namespace

extern "C" __attribute__((visibility("default"))) const KdrtOiioPlugin* kdrt_oiio_plugin(void) { return &plugin; }
