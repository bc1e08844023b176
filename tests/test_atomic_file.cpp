// detail::AtomicFile and the writers built on it (images, id maps): a file is
// replaced whole or not at all, and links and special files are never
// replaced.
#include "common/atomic_file.h"
#include "common/terminal_text.h"

#include <kdrt/error.h>
#include <kdrt/image.h>
#include <kdrt/render.h>

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <csignal>
#include <cstring>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace kdrt;

namespace {

struct TempDir {
    fs::path path;
    TempDir() {
        std::random_device random;
        path = fs::temp_directory_path() / ("kdrt-test-atomic-" + std::to_string(random()) + std::to_string(random()));
        fs::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::permissions(path, fs::perms::owner_all, fs::perm_options::add, ec);
        fs::remove_all(path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    std::size_t entries() const { return static_cast<std::size_t>(std::distance(fs::directory_iterator(path), {})); }
};

std::string read_text(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

std::span<const unsigned char> bytes_of(const std::string& s) {
    return {reinterpret_cast<const unsigned char*>(s.data()), s.size()};
}

bool message_has(const Error& e, const std::string& part) { return std::string(e.what()).find(part) != std::string::npos; }

}  // namespace

TEST_CASE("write_file_atomically replaces a file and leaves no temporary", "[io]") {
    TempDir dir;
    const fs::path target = dir.path / "out.bin";
    write_text(target, "old contents");
    detail::write_file_atomically(target, bytes_of("new"));
    CHECK(read_text(target) == "new");
    CHECK(dir.entries() == 1);
}

TEST_CASE("remove_live_temporaries unlinks the temporaries of unfinished atomic files only", "[io]") {
    TempDir dir;
    const fs::path done_target = dir.path / "done.bin", live_target = dir.path / "live.bin";
    {
        detail::AtomicFile done(done_target);
        done.write("a", 1);
        done.commit();
        detail::AtomicFile discarded(dir.path / "discarded.bin");
    }
    detail::AtomicFile live(live_target);
    live.write("partial", 7);
    const fs::path live_temporary = live.temporary();
    CHECK(fs::exists(live_temporary));
    // What a SIGTERM handler does before the process ends: no temporary left beside live.bin.
    detail::remove_live_temporaries();
    CHECK_FALSE(fs::exists(live_temporary));
    CHECK(read_text(done_target) == "a");
    CHECK(dir.entries() == 1);
    // A second call finds nothing; a new file is tracked again.
    detail::remove_live_temporaries();
    detail::AtomicFile next(dir.path / "next.bin");
    CHECK(fs::exists(next.temporary()));
    detail::remove_live_temporaries();
    CHECK_FALSE(fs::exists(next.temporary()));
}

TEST_CASE("a failed atomic write keeps the previous file and removes the temporary", "[io]") {
    TempDir dir;
    const fs::path target = dir.path / "out.bin";
    write_text(target, "previous");
    {
        detail::AtomicFile file(target);
        file.write("partial", 7);
        CHECK(fs::exists(file.temporary()));
        CHECK(file.temporary().filename().string().rfind(detail::temporary_file_prefix(target), 0) == 0);
        CHECK(file.temporary().parent_path() == target.parent_path());
        // No commit: the writer failed (an exception unwound past it).
    }
    CHECK(read_text(target) == "previous");
    CHECK(dir.entries() == 1);

    SECTION("a rename that fails (the target became a non-empty directory) reports the file and the OS error") {
        const fs::path busy = dir.path / "busy";
        detail::AtomicFile file(busy);
        file.write("data", 4);
        fs::create_directories(busy / "child");
        try {
            file.commit();
            FAIL("commit over a directory succeeded");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::Io);
            CHECK(message_has(e, busy.string()));
        }
        CHECK(fs::is_directory(busy / "child"));
        CHECK(dir.entries() == 2);  // out.bin and busy/: the temporary is gone
    }
}

// A file-size limit (RLIMIT_FSIZE, SIGXFSZ ignored) makes write() fail with
// EFBIG part way through: a full disk, without filling one.
struct FileSizeLimit {
    rlimit saved{};
    void (*saved_handler)(int);
    explicit FileSizeLimit(rlim_t bytes) {
        saved_handler = std::signal(SIGXFSZ, SIG_IGN);
        ::getrlimit(RLIMIT_FSIZE, &saved);
        rlimit limited = saved;
        limited.rlim_cur = bytes;
        ::setrlimit(RLIMIT_FSIZE, &limited);
    }
    ~FileSizeLimit() {
        ::setrlimit(RLIMIT_FSIZE, &saved);
        std::signal(SIGXFSZ, saved_handler);
    }
    FileSizeLimit(const FileSizeLimit&) = delete;
    FileSizeLimit& operator=(const FileSizeLimit&) = delete;
};

TEST_CASE("a write that runs out of space fails naming the file and the OS error, keeping the previous file", "[io]") {
    TempDir dir;
    const fs::path target = dir.path / "out.bin";
    write_text(target, "previous");
    const std::string big(100000, 'x');
    Image image(256, 256);
    std::mt19937 random(7);  // noise: no format compresses it under the limit
    for (float& c : image.rgb) c = std::uniform_real_distribution<float>(0.0f, 1.0f)(random);
    {
        FileSizeLimit limit(4096);
        try {
            detail::write_file_atomically(target, bytes_of(big));
            FAIL("no error");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::Io);
            CHECK(message_has(e, target.string()));
            CHECK(message_has(e, std::strerror(EFBIG)));
        }
        // Every image format, including JPEG (whose library exits on a failed write).
        // .sgi and .fits: writers without an I/O proxy that do not check their own writes.
        for (const char* ext : {".png", ".jpg", ".exr", ".tif", ".ppm", ".hdr", ".bmp", ".sgi", ".fits"}) {
            const fs::path picture = dir.path / (std::string("img") + ext);
            write_text(picture, "previous");
            INFO(picture);
            CHECK_THROWS_WITH(write_image(picture, image), Catch::Contains(picture.string()));
            CHECK(read_text(picture) == "previous");
        }
    }
    CHECK(read_text(target) == "previous");
    CHECK(dir.entries() == 10);  // the previous files only: no temporaries
}

TEST_CASE("symlinks, FIFOs, devices and directories are refused as targets", "[io]") {
    TempDir dir;
    const fs::path real = dir.path / "real.txt";
    write_text(real, "keep me");

    const fs::path link = dir.path / "link.txt";
    fs::create_symlink(real, link);
    CHECK_THROWS_WITH(detail::write_file_atomically(link, bytes_of("x")), Catch::Contains("symbolic link"));
    CHECK(fs::is_symlink(link));
    CHECK(read_text(real) == "keep me");

    const fs::path fifo = dir.path / "fifo";
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    CHECK_THROWS_WITH(detail::write_file_atomically(fifo, bytes_of("x")), Catch::Contains("not a regular file"));
    CHECK(fs::is_fifo(fifo));

    if (fs::exists("/dev/null")) {
        CHECK_THROWS_WITH(detail::check_output_target("/dev/null"), Catch::Contains("not a regular file"));
        CHECK(fs::is_character_file("/dev/null"));
    }
    CHECK_THROWS_WITH(detail::write_file_atomically(dir.path, bytes_of("x")), Catch::Contains("directory"));
    CHECK_THROWS_WITH(detail::write_file_atomically(dir.path / "missing" / "x", bytes_of("x")),
                      Catch::Contains("missing"));
    CHECK(dir.entries() == 3);  // real.txt, link.txt, fifo: no temporaries
}

TEST_CASE("an unwritable directory is reported before anything is written", "[io]") {
    if (::geteuid() == 0) {
        WARN("running as root: permission bits do not stop writes, skipped");
        return;
    }
    TempDir dir;
    const fs::path sub = dir.path / "ro";
    fs::create_directories(sub);
    fs::permissions(sub, fs::perms::owner_read | fs::perms::owner_exec);
    CHECK_THROWS_WITH(detail::check_output_target(sub / "x.png"), Catch::Contains("not writable"));
    fs::permissions(sub, fs::perms::owner_all);
}

TEST_CASE("write_image goes through a temporary and refuses bad images", "[io]") {
    TempDir dir;
    Image image(4, 3);
    for (float& c : image.rgb) c = 0.5f;
    for (const char* ext : {".png", ".exr", ".ppm", ".tif", ".jpg", ".hdr", ".bmp"}) {
        const fs::path target = dir.path / (std::string("img") + ext);
        write_text(target, "previous");
        INFO(target);
        write_image(target, image);
        const Image back = read_image(target);
        CHECK(back.width == 4);
        CHECK(back.height == 3);
    }
    CHECK(dir.entries() == 7);  // no temporaries

    SECTION("an image whose pixels do not match its size is an InvalidArgument, and nothing is written") {
        Image broken;
        broken.width = broken.height = 100;
        const fs::path target = dir.path / "img.png";
        const std::string before = read_text(target);
        try {
            write_image(target, broken);
            FAIL("no error");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidArgument);
            CHECK(message_has(e, "img.png"));
        }
        CHECK(read_text(target) == before);
    }
    SECTION("a symlink at the target is refused and its target kept") {
        const fs::path link = dir.path / "link.png";
        fs::create_symlink(dir.path / "img.png", link);
        const std::string before = read_text(dir.path / "img.png");
        CHECK_THROWS_AS(write_image(link, image), Error);
        CHECK(fs::is_symlink(link));
        CHECK(read_text(dir.path / "img.png") == before);
    }
}

TEST_CASE("write_id_map refuses a symlink and keeps the previous file", "[io]") {
    TempDir dir;
    RenderResult r;
    r.image = Image(2, 1);
    r.ids = {1, -1};
    r.hit_t = {1.0f, 0.0f};
    const fs::path target = dir.path / "ids.bin";
    kdrt::write_id_map(target, r);
    CHECK(fs::file_size(target) == 16);
    fs::create_symlink(target, dir.path / "link.bin");
    CHECK_THROWS_WITH(kdrt::write_id_map(dir.path / "link.bin", r), Catch::Contains("symbolic link"));
    CHECK(fs::file_size(target) == 16);
}

TEST_CASE("escape_for_terminal makes control characters visible", "[io]") {
    using detail::escape_for_terminal;
    CHECK(escape_for_terminal("opencl:gpu") == "opencl:gpu");
    CHECK(escape_for_terminal("a\x1b[2Jb") == "a\\e[2Jb");
    CHECK(escape_for_terminal("line\nnext\t\x07") == "line\\nnext\\t\\x07");
    CHECK(escape_for_terminal("keep\nlines", true) == "keep\nlines");
    CHECK(escape_for_terminal("\xc2\x9b" "31m") == "\\u009b31m");  // C1 CSI in UTF-8
    CHECK(escape_for_terminal("caf\xc3\xa9") == "caf\xc3\xa9");     // other UTF-8 kept
}
