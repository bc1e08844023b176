#include "scene/regular_file_io.h"

#include <assimp/IOStream.hpp>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string_view>

namespace kdrt::detail {
namespace {

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

RegularFileIo::~RegularFileIo() {
    while (!open_.empty()) delete *open_.begin();  // each one erases itself
}

void RegularFileIo::Close(Assimp::IOStream* stream) { delete stream; }

void RegularFileIo::note_missing(const std::string& file) const {
    if (std::find(missing_.begin(), missing_.end(), file) == missing_.end()) missing_.push_back(file);
}

bool RegularFileIo::Exists(const char* file) const {
    if (is_regular(file)) return true;
    if (file != nullptr) note_missing(file);
    return false;
}

Assimp::IOStream* RegularFileIo::Open(const char* file, const char* mode) {
    // Model files are only ever read.
    if (mode == nullptr || std::string_view(mode).find_first_of("wa+") != std::string_view::npos) return nullptr;
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
