#include "scene/assimp_log_capture.h"

#include <assimp/DefaultLogger.hpp>
#include <assimp/LogStream.hpp>

namespace kdrt::detail {
namespace {

std::mutex logger_mutex;

class CollectingStream : public Assimp::LogStream {
public:
    explicit CollectingStream(std::vector<std::string>& out) : out_(out) {}
    void write(const char* message) override {
        std::string m = message ? message : "";
        // "Warn,  T0: text\n" -> "text"
        if (const std::size_t colon = m.find(": "); colon != std::string::npos && colon < 16) m.erase(0, colon + 2);
        while (!m.empty() && (m.back() == '\n' || m.back() == '\r')) m.pop_back();
        if (out_.size() < 1000) out_.push_back(std::move(m));
    }

private:
    std::vector<std::string>& out_;
};

}  // namespace

AssimpLogCapture::AssimpLogCapture() : lock_(logger_mutex) {
    if (!Assimp::DefaultLogger::isNullLogger()) return;
    // No name, no default streams: no log file, nothing on the console.
    Assimp::Logger* logger = Assimp::DefaultLogger::create(nullptr, Assimp::Logger::NORMAL, 0);
    // The logger owns the stream and deletes it in kill().
    logger->attachStream(new CollectingStream(messages_), Assimp::Logger::Warn | Assimp::Logger::Err);
    installed_ = true;
}

AssimpLogCapture::~AssimpLogCapture() {
    if (installed_) Assimp::DefaultLogger::kill();
}

}  // namespace kdrt::detail
