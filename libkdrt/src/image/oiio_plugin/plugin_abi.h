// The C interface between libkdrt and its OpenImageIO plugin, libkdrt_oiio.so.
// OpenImageIO pulls in some 260 shared libraries (OpenCV, FFmpeg, GDAL, ...)
// that take a third of a second to load, so libkdrt writes PNG, PPM and PFM
// itself and loads the plugin only for the other formats (image/oiio_plugin.cpp).
// Plain C types only: the plugin and libkdrt share no C++ objects.
#pragma once

#include <stddef.h>

extern "C" {

// Receives encoded bytes, a pixel buffer request, or an error message.
typedef void (*KdrtOiioSink)(void* context, const void* bytes, size_t size);
typedef float* (*KdrtOiioPixels)(void* context, int width, int height, int channels);
typedef void (*KdrtOiioText)(void* context, const char* text);

enum { KDRT_OIIO_ABI_VERSION = 1 };

// Results of KdrtOiioPlugin::write.
enum {
    KDRT_OIIO_ENCODE_FAILED = 0,   // the image could not be encoded (error says why)
    KDRT_OIIO_ENCODED = 1,         // the file's bytes went to the sink; nothing was written
    KDRT_OIIO_WROTE_FILE = 2,      // the writer has no I/O proxy: it wrote `file`, which reads back whole
    KDRT_OIIO_WRITE_FAILED = -1,   // writing `file` failed (error says why)
    KDRT_OIIO_NO_READ_BACK = -2,   // `file` was written but does not read back (a writer that hides disk errors)
};

struct KdrtOiioPlugin {
    int abi_version;  // KDRT_OIIO_ABI_VERSION
    // 1 when OpenImageIO has a writer for the extension of `path`.
    int (*has_writer)(const char* path);
    // Encodes width x height RGB pixels (floats when is_float, else bytes) in
    // the format named by `format_path`'s extension: into the sink when the
    // writer takes an I/O proxy, else into `file`.
    int (*write)(const char* format_path, const char* file, int width, int height, int is_float, const void* pixels,
                 KdrtOiioSink sink, void* sink_context, KdrtOiioText error, void* error_context);
    // Reads the first subimage as floats into the buffer `pixels` returns; 1 on success.
    int (*read)(const char* path, KdrtOiioPixels pixels, void* pixels_context, KdrtOiioText error, void* error_context);
};

// The one symbol the plugin exports.
const KdrtOiioPlugin* kdrt_oiio_plugin(void);
#define KDRT_OIIO_PLUGIN_SYMBOL "kdrt_oiio_plugin"
}
