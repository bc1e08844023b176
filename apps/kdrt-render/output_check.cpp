#include "output_check.h"

#include "frame_names.h"

#include "common/atomic_file.h"

#include <kdrt/error.h>

#include <sys/stat.h>

#include <filesystem>
#include <map>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace kdrt::cli {
namespace {

namespace fs = std::filesystem;

struct NamedFile {
    std::string option, path;
};

// Who a path is: its inode when it exists, and its absolute name with the
// directory's links resolved (the file itself may not exist yet).
struct Identity {
    bool exists = false;
    std::pair<dev_t, ino_t> inode{};
    std::string name;
};

class Identities {
public:
    Identity of(const std::string& path) {
        Identity id;
        struct stat st {};
        if (::stat(path.c_str(), &st) == 0) {
            id.exists = true;
            id.inode = {st.st_dev, st.st_ino};
        }
        const fs::path p(path);
        id.name = (directory(p.parent_path()) / p.filename()).lexically_normal().string();
        return id;
    }

private:
    // Frames share a directory: it is resolved once.
    const fs::path& directory(const fs::path& dir) {
        auto [it, fresh] = resolved_.try_emplace(dir.string());
        if (fresh) {
            std::error_code ec;
            const fs::path absolute = fs::absolute(dir.empty() ? fs::path(".") : dir, ec);
            it->second = ec ? absolute : fs::weakly_canonical(absolute, ec);
            if (ec) it->second = absolute;
        }
        return it->second;
    }
    std::map<std::string, fs::path> resolved_;
};

bool same(const Identity& a, const Identity& b) {
    return (a.exists && b.exists && a.inode == b.inode) || a.name == b.name;
}

// In the order their files are written: every frame's image, every frame's id map, the tree.
std::vector<NamedFile> planned_outputs(const Args& a) {
    std::vector<NamedFile> outputs;
    const std::pair<const char*, const std::string*> per_frame[] = {{"--output", &a.output}, {"--aov-ids", &a.aov_ids}};
    for (const auto& [option, path] : per_frame)
        if (!path->empty())
            for (int frame = 0; frame < a.frames; ++frame) outputs.push_back({option, frame_file_name(*path, frame, a.frames)});
    if (!a.save_tree.empty()) outputs.push_back({"--save-tree", a.save_tree});
    return outputs;
}

}  // namespace

void check_outputs(const Args& a) {
    std::vector<NamedFile> inputs{{"the scene", a.scene_path}};
    if (!a.load_tree.empty()) inputs.push_back({"--load-tree", a.load_tree});
    Identities identities;
    std::vector<Identity> input_ids;
    for (const NamedFile& in : inputs) input_ids.push_back(identities.of(in.path));

    const std::vector<NamedFile> outputs = planned_outputs(a);
    std::map<std::string, std::size_t> by_name;
    std::map<std::pair<dev_t, ino_t>, std::size_t> by_inode;
    for (std::size_t i = 0; i < outputs.size(); ++i) {
        const auto& [option, path] = outputs[i];
        try {
            kdrt::detail::check_output_target(path);
        } catch (const Error& e) {
            throw UsageError(option + " " + e.what());
        }
        const Identity id = identities.of(path);
        for (std::size_t k = 0; k < inputs.size(); ++k)
            if (same(id, input_ids[k]))
                throw UsageError(option + " " + path + " is " + inputs[k].option + " " + inputs[k].path +
                                 ": writing it would destroy the input");
        auto earlier = by_name.find(id.name);
        if (earlier == by_name.end() && id.exists) {
            const auto linked = by_inode.find(id.inode);
            if (linked != by_inode.end()) earlier = by_name.find(identities.of(outputs[linked->second].path).name);
        }
        if (earlier != by_name.end())
            throw UsageError(option + " " + path + " and " + outputs[earlier->second].option + " " +
                             outputs[earlier->second].path + " are the same file");
        by_name.emplace(id.name, i);
        if (id.exists) by_inode.emplace(id.inode, i);
    }
}

}  // namespace kdrt::cli
