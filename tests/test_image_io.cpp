// Image files: PNG/PPM/PFM written by kdrt itself, float TIFF and the rest
// through the OpenImageIO plugin; values read back, the sRGB encoding.
#include "temp_dir.h"

#include <kdrt/error.h>
#include <kdrt/image.h>

#include <catch2/catch.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <limits>

using namespace kdrt;
namespace fs = std::filesystem;

namespace {

// Values that an 8-bit file cannot hold: negative, above 1, tiny, huge.
Image awkward_image() {
    Image image(5, 3);
    const float values[] = {0.0f, 1.0f, 0.5f, -2.25f, 3.0e7f, 1.0e-30f, 0.1f, 123.456f, -0.0f, 65504.5f};
    for (std::size_t i = 0; i < image.rgb.size(); ++i) image.rgb[i] = values[i % std::size(values)] * (1.0f + i);
    return image;
}

std::string file_bytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

float little_endian_float(const std::string& bytes, std::size_t at) {
    std::uint32_t bits = 0;
    for (int b = 0; b < 4; ++b) bits |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at + b])) << (8 * b);
    return std::bit_cast<float>(bits);
}

}  // namespace

TEST_CASE("linear 8-bit encoding is round(255 c) with halves rounded up, as std::lround gives it", "[io]") {
    // Near every rounding boundary (k + 0.5) / 255, a few ulps either side,
    // and a sweep of one float in 251 over [0, 1].
    std::size_t differ = 0, checked = 0;
    auto check = [&](float c) {
        differ += to_8bit(c) != std::lround(255.0f * c);
        ++checked;
    };
    for (int k = 0; k < 255; ++k) {
        float c = (static_cast<float>(k) + 0.5f) / 255.0f;
        for (int i = 0; i < 16; ++i) c = std::nextafter(c, 0.0f);
        for (int i = 0; i < 33; ++i, c = std::nextafter(c, 1.0f)) check(c);
    }
    for (std::uint32_t bits = 0; bits <= std::bit_cast<std::uint32_t>(1.0f); bits += 251) check(std::bit_cast<float>(bits));
    INFO(checked << " values");
    CHECK(differ == 0);
    CHECK(to_8bit(127.5f / 255.0f) == 128);
    CHECK(to_8bit(-0.0f) == 0);
    CHECK(to_8bit(1.5f) == 255);
    CHECK(to_8bit(std::numeric_limits<float>::quiet_NaN()) == 0);
}

TEST_CASE("sRGB encoding follows IEC 61966-2-1, linear is FORMAT.md's round(255 c)", "[io]") {
    CHECK(to_8bit_srgb(0.5f) == 188);  // 1.055 * 0.5^(1/2.4) - 0.055 = 0.7354 -> 187.5
    CHECK(to_8bit(0.5f) == 128);
    CHECK(to_8bit_srgb(0.0f) == 0);
    CHECK(to_8bit_srgb(1.0f) == 255);
    CHECK(to_8bit_srgb(0.0031308f * 0.5f) == std::lround(255 * 12.92 * 0.0031308 * 0.5));  // the linear segment
    CHECK(to_8bit_srgb(0.18f) == 118);  // middle grey, not 2.2-gamma's 117
    CHECK(to_8bit_srgb(-1.0f) == 0);
    CHECK(to_8bit_srgb(2.0f) == 255);
    CHECK(to_8bit_srgb(std::numeric_limits<float>::quiet_NaN()) == 0);
    for (int i = 1; i < 256; ++i) CHECK(to_8bit_srgb(i / 255.0f) >= to_8bit_srgb((i - 1) / 255.0f));
}

TEST_CASE("8-bit files read back as the encoded bytes / 255", "[io]") {
    test::TempDir dir("kdrt-image-io");
    Image image(3, 2);
    const float values[] = {0.5f, 0.0f, 1.0f, 0.18f, 0.25f, 0.75f};
    for (std::size_t i = 0; i < image.rgb.size(); ++i) image.rgb[i] = values[i % 6] * (i < 6 ? 1.0f : 0.9f);
    for (const char* ext : {".png", ".ppm", ".tif", ".bmp"})
        for (Encoding encoding : {Encoding::Linear, Encoding::Srgb}) {
            INFO(ext << (encoding == Encoding::Srgb ? " srgb" : " linear"));
            const fs::path file = dir.path / (std::string("eight") + ext);
            write_image(file, image, {encoding, false});
            const Image back = read_image(file);
            REQUIRE(back.width == 3);
            REQUIRE(back.height == 2);
            for (std::size_t i = 0; i < image.rgb.size(); ++i) {
                const int byte = encoding == Encoding::Srgb ? to_8bit_srgb(image.rgb[i]) : to_8bit(image.rgb[i]);
                CHECK(std::lround(back.rgb[i] * 255.0f) == byte);
            }
            if (encoding == Encoding::Srgb) CHECK(std::lround(back.rgb[0] * 255.0f) == 188);
        }
}

TEST_CASE("PFM files hold the floats exactly, little-endian, bottom row first", "[io]") {
    test::TempDir dir("kdrt-image-io");
    const Image image = awkward_image();
    const fs::path file = dir.path / "floats.pfm";
    write_image(file, image);
    const std::string bytes = file_bytes(file);
    const std::string header = "PF\n5 3\n-1.0\n";
    REQUIRE(bytes.substr(0, header.size()) == header);
    REQUIRE(bytes.size() == header.size() + 5 * 3 * 3 * 4);
    // The first stored row is the image's bottom row (y = 2).
    CHECK(std::bit_cast<std::uint32_t>(little_endian_float(bytes, header.size())) ==
          std::bit_cast<std::uint32_t>(image.at(0, 2).x));
    CHECK(little_endian_float(bytes, bytes.size() - 4) == image.at(4, 0).z);

    const Image back = read_image(file);
    REQUIRE(back.width == 5);
    REQUIRE(back.height == 3);
    for (std::size_t i = 0; i < image.rgb.size(); ++i)
        CHECK(std::bit_cast<std::uint32_t>(back.rgb[i]) == std::bit_cast<std::uint32_t>(image.rgb[i]));

    SECTION("big-endian and grey files are read too") {
        std::string be = "PF\n1 2\n1.0\n", grey = "Pf\n2 1\n-1\n";
        for (float v : {1.5f, -2.0f, 0.25f, 8.0f, 16.0f, 32.0f}) {
            const std::uint32_t bits = std::bit_cast<std::uint32_t>(v);
            for (int b = 3; b >= 0; --b) be += static_cast<char>(bits >> (8 * b));
        }
        for (float v : {0.5f, 4.0f}) {
            const std::uint32_t bits = std::bit_cast<std::uint32_t>(v);
            for (int b = 0; b < 4; ++b) grey += static_cast<char>(bits >> (8 * b));
        }
        const Image b = read_image(dir.write("be.pfm", be));
        CHECK(b.at(0, 1) == glm::vec3(1.5f, -2.0f, 0.25f));  // stored first: the bottom row
        CHECK(b.at(0, 0) == glm::vec3(8.0f, 16.0f, 32.0f));
        const Image g = read_image(dir.write("grey.pfm", grey));
        CHECK(g.at(1, 0) == glm::vec3(4.0f));
    }
    SECTION("broken files are refused naming the file") {
        for (const std::string& broken : {std::string("PF\n5 3\n-1.0\n1234"), std::string("PF\n0 3\n-1\n"),
                                          std::string("PF\n5 3\nnan\n"), std::string("P3\n1 1\n255\n1 2 3\n"),
                                          std::string("PF\n99999999999 3\n-1\n")}) {
            INFO(broken);
            CHECK_THROWS_WITH(read_image(dir.write("broken.pfm", broken)), Catch::Contains("broken.pfm"));
        }
    }
}

TEST_CASE("float TIFF holds the floats exactly, float samples are for TIFF only", "[io]") {
    test::TempDir dir("kdrt-image-io");
    const Image image = awkward_image();
    ImageWriteOptions options;
    options.float_samples = true;
    CHECK(image_stores_floats("a.tif", options));
    CHECK_FALSE(image_stores_floats("a.tif"));
    CHECK(image_stores_floats("a.PFM"));
    for (const char* name : {"floats.tif", "floats.tiff", "floats.exr"}) {
        INFO(name);
        write_image(dir.path / name, image, options.float_samples && fs::path(name).extension() != ".exr"
                                                ? options : ImageWriteOptions{});
        const Image back = read_image(dir.path / name);
        REQUIRE(back.rgb.size() == image.rgb.size());
        for (std::size_t i = 0; i < image.rgb.size(); ++i) CHECK(back.rgb[i] == image.rgb[i]);
    }
    // Without the option a TIFF is 8-bit: the values are clamped.
    write_image(dir.path / "eight.tif", image);
    CHECK(read_image(dir.path / "eight.tif").rgb[3] == 0.0f);
    try {
        write_image(dir.path / "x.png", image, options);
        FAIL("no error");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::InvalidArgument);
        CHECK_THAT(e.what(), Catch::Contains("x.png") && Catch::Contains("TIFF"));
    }
    CHECK_FALSE(fs::exists(dir.path / "x.png"));
}

TEST_CASE("PNG files are read whatever their layout, with no transfer curve applied", "[io]") {
    test::TempDir dir("kdrt-image-io");
    Image image(2, 2);
    image.set(1, 0, {0.2f, 0.4f, 0.6f});
    write_image(dir.path / "a.png", image, {Encoding::Srgb, false});
    const std::string bytes = file_bytes(dir.path / "a.png");
    CHECK(bytes.find("sRGB") != std::string::npos);  // sRGB-encoded files say so
    write_image(dir.path / "b.png", image);
    CHECK(file_bytes(dir.path / "b.png").find("sRGB") == std::string::npos);  // linear ones carry no colour chunk
    const Image back = read_image(dir.path / "a.png");
    CHECK(std::lround(back.at(1, 0).y * 255) == to_8bit_srgb(0.4f));
    CHECK_THROWS_WITH(read_image(dir.write("bad.png", "\x89PNG\r\n\x1a\n garbage")), Catch::Contains("bad.png"));
}
