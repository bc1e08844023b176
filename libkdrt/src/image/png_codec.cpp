#include "image/png_codec.h"

#include <kdrt/error.h>

#include <png.h>
#include <zlib.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>

namespace kdrt::detail {

namespace {

// libpng reports errors by longjmp: the message is kept here, and no C++
// object with a destructor lives in the frames it jumps over.
struct PngContext {
    std::vector<unsigned char>* out = nullptr;
    const std::string* in = nullptr;
    std::size_t read_at = 0;
    std::vector<png_byte> pixels;  // decoded rows: sized between setjmp and longjmp, so kept out of locals
    std::vector<png_bytep> rows;
    char message[256] = "";
};

void on_error(png_structp png, png_const_charp message) {
    auto* c = static_cast<PngContext*>(png_get_error_ptr(png));
    std::snprintf(c->message, sizeof c->message, "%s", message);
    png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}

void on_write(png_structp png, png_bytep data, png_size_t size) {
    auto* c = static_cast<PngContext*>(png_get_io_ptr(png));
    c->out->insert(c->out->end(), data, data + size);
}
void on_flush(png_structp) {}

void on_read(png_structp png, png_bytep data, png_size_t size) {
    auto* c = static_cast<PngContext*>(png_get_io_ptr(png));
    if (c->in->size() - c->read_at < size) png_error(png, "truncated file");
    std::memcpy(data, c->in->data() + c->read_at, size);
    c->read_at += size;
}

}  // namespace

std::vector<unsigned char> encode_png(const unsigned char* rgb, int width, int height, bool srgb) {
    std::vector<unsigned char> out;
    std::vector<png_bytep> rows(static_cast<std::size_t>(height));
    for (int y = 0; y < height; ++y)
        rows[y] = const_cast<png_bytep>(rgb + static_cast<std::size_t>(y) * width * 3);
    PngContext context;
    context.out = &out;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &context, on_error, on_warning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!info) {
        png_destroy_write_struct(&png, nullptr);
        throw Error(ErrorCode::Io, "cannot encode the PNG image: out of memory");
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        throw Error(ErrorCode::Io, std::string("cannot encode the PNG image: ") + context.message);
    }
    png_set_write_fn(png, &context, on_write, on_flush);
    png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (srgb) png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    // Written for speed: level 1, the Up filter and zlib's RLE strategy encode
    // several times faster than the defaults for a somewhat larger file.
    png_set_compression_level(png, 1);
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
    png_set_compression_strategy(png, Z_RLE);
    png_set_rows(png, info, rows.data());
    png_write_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
    png_destroy_write_struct(&png, &info);
    return out;
}

Image decode_png(const std::string& bytes, const std::string& name) {
    if (bytes.size() < 8 || png_sig_cmp(reinterpret_cast<png_const_bytep>(bytes.data()), 0, 8) != 0)
        throw Error(ErrorCode::Io, name + ": cannot read image: not a PNG file");
    PngContext context;
    context.in = &bytes;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &context, on_error, on_warning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!info) {
        png_destroy_read_struct(&png, nullptr, nullptr);
        throw Error(ErrorCode::Io, name + ": cannot read image: out of memory");
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        throw Error(ErrorCode::Io, name + ": cannot read image: " + context.message);
    }
    png_set_read_fn(png, &context, on_read);
    png_set_user_limits(png, 1u << 20, 1u << 20);
    png_read_info(png, info);
    png_set_expand(png);        // palette -> RGB, grey < 8 bits -> 8 bits, tRNS -> alpha
    png_set_strip_alpha(png);
    png_set_gray_to_rgb(png);
    png_read_update_info(png, info);
    const png_uint_32 width = png_get_image_width(png, info), height = png_get_image_height(png, info);
    const int depth = png_get_bit_depth(png, info);
    const std::size_t row_bytes = png_get_rowbytes(png, info);
    if (png_get_channels(png, info) != 3 || (depth != 8 && depth != 16) || row_bytes != width * 3 * (depth / 8))
        png_error(png, "unsupported pixel layout");
    context.pixels.resize(row_bytes * height);
    context.rows.resize(height);
    for (png_uint_32 y = 0; y < height; ++y) context.rows[y] = context.pixels.data() + y * row_bytes;
    png_read_image(png, context.rows.data());
    png_read_end(png, nullptr);
    png_destroy_read_struct(&png, &info, nullptr);

    const std::vector<png_byte>& pixels = context.pixels;
    Image image(static_cast<int>(width), static_cast<int>(height));
    for (std::size_t i = 0; i < image.rgb.size(); ++i)
        image.rgb[i] = depth == 8 ? static_cast<float>(pixels[i]) / 255.0f
                                  : static_cast<float>(pixels[2 * i] * 256 + pixels[2 * i + 1]) / 65535.0f;
    return image;
}

}  // namespace kdrt::detail
