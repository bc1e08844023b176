#include "scene/regular_file_io.h"

#include <assimp/IOStream.hpp>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string_view>

namespace kdrt::detail {
namespace {

bool inside(const std::filesystem::path& file, const std::filesystem::path& dir) {
    const auto [d, f] = std::mismatch(dir.begin(), dir.end(), file.begin(), file.end());
    return d == dir.end() && f != file.end();
}

bool is_regular(const char* file) {
    std::error_code ec;
    return file != nullptr && std::filesystem::is_regular_file(file, ec);
}

// A file stream that tells its RegularFileIo when it is gone.
class TrackedStream : public Assimp::IOStream {
public:
    TrackedStream(Assimp::IOStream* inner, RegularFileIo& owner) : inner_(inner), owner_(owner) {}
    ~TrackedStream() override { owner_.forget(this); }
    size_t Read(void* buffer, size_t size, size_t count) override { return inner_->Read(buffer, size, count); }
    size_t Write(const void* buffer, size_t size, size_t count) override { return inner_->Write(buffer, size, count); }
    aiReturn Seek(size_t offset, aiOrigin origin) override { return inner_->Seek(offset, origin); }
    size_t Tell() const override { return inner_->Tell(); }
    size_t FileSize() const override { return inner_->FileSize(); }
    void Flush() override { inner_->Flush(); }

private:
    std::unique_ptr<Assimp::IOStream> inner_;
    RegularFileIo& owner_;
};

}  // namespace

static std::filesystem::path resolved(const std::filesystem::path& p) {
    std::error_code ec;
    std::filesystem::path r = std::filesystem::weakly_canonical(std::filesystem::absolute(p, ec), ec);
    return ec ? std::filesystem::path() : r;
}

RegularFileIo::RegularFileIo(const std::filesystem::path& model, bool allow_outside)
    : model_(resolved(model)), folder_(resolved(model).parent_path()), allow_outside_(allow_outside) {
    // The folder as given (a model reached through a symbolic link names files beside the link).
    std::error_code ec;
    const std::filesystem::path given = std::filesystem::absolute(model, ec).parent_path();
    if (const std::filesystem::path f = resolved(given); !ec && !f.empty()) folder_ = f;
}

bool RegularFileIo::allowed(const char* file) const {
    if (allow_outside_ || file == nullptr) return true;
    const std::filesystem::path p = resolved(file);
    if (!p.empty() && (p == model_ || (!folder_.empty() && inside(p, folder_)))) return true;
    if (std::find(refused_.begin(), refused_.end(), file) == refused_.end()) refused_.push_back(file);
    return false;
}

RegularFileIo::~RegularFileIo() {
    while (!open_.empty()) delete *open_.begin();  // each one erases itself
}

void RegularFileIo::Close(Assimp::IOStream* stream) { delete stream; }

void RegularFileIo::note_missing(const std::string& file) const {
    if (std::find(missing_.begin(), missing_.end(), file) == missing_.end()) missing_.push_back(file);
}

bool RegularFileIo::Exists(const char* file) const {
    if (!allowed(file)) return false;
    if (is_regular(file)) return true;
    if (file != nullptr) note_missing(file);
    return false;
}

Assimp::IOStream* RegularFileIo::Open(const char* file, const char* mode) {
    // Model files are only ever read.
    if (mode == nullptr || std::string_view(mode).find_first_of("wa+") != std::string_view::npos) return nullptr;
    if (!allowed(file)) return nullptr;
    if (!is_regular(file)) {
        if (file != nullptr) note_missing(file);
        return nullptr;
    }
    Assimp::IOStream* inner = Assimp::DefaultIOSystem::Open(file, mode);
    if (!inner) return nullptr;
    auto* stream = new TrackedStream(inner, *this);
    open_.insert(stream);
    return stream;
}

}  // namespace kdrt::detail
