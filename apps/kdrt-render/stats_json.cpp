#include "stats_json.h"

#include <kdrt/enum_names.h>

#include <iostream>

namespace kdrt::cli {

nlohmann::ordered_json tree_stats_json(const KdTreeStats& s) {
    return {{"nodes", s.nodes},
            {"inner_nodes", s.inner_nodes},
            {"leaves", s.leaves},
            {"empty_leaves", s.empty_leaves},
            {"max_leaf_depth", s.max_leaf_depth},
            {"mean_leaf_depth", s.mean_leaf_depth},
            {"mean_objects_per_leaf", s.mean_objects_per_leaf},
            {"duplication", s.duplication},
            {"sah_cost", s.sah_cost},
            {"bytes", {{"nodes", s.node_bytes},
                       {"leaf_objects", s.leaf_object_bytes},
                       {"ropes", s.rope_bytes},
                       {"total", s.total_bytes()}}},
            // Per object of the scene (per triangle in a mesh): leaf lists are the object ids (a leaf node
            // holds its list's range, there are no leaf records).
            {"bytes_per_object", {{"nodes", s.per_object(s.node_bytes)},
                                  {"leaf_lists", s.per_object(s.leaf_object_bytes)},
                                  {"ropes", s.per_object(s.rope_bytes)},
                                  {"total", s.per_object(s.total_bytes())}}}};
}

nlohmann::ordered_json bvh_stats_json(const BvhStats& s) {
    return {{"nodes", s.nodes},
            {"leaves", s.leaves},
            {"empty_slots", s.empty_slots},
            {"depth", s.depth},
            {"mean_leaf_size", s.mean_leaf_size},
            {"sah_cost", s.sah_cost},
            {"build_sah_cost", s.build_sah_cost},
            {"bytes", {{"nodes", s.node_bytes}, {"leaf_objects", s.leaf_object_bytes}, {"total", s.total_bytes()}}},
            {"bytes_per_object", {{"nodes", s.per_object(s.node_bytes)},
                                  {"leaf_lists", s.per_object(s.leaf_object_bytes)},
                                  {"total", s.per_object(s.total_bytes())}}}};
}

nlohmann::ordered_json stats_json(const Args& a, const Scene& scene, const RenderOptions& o,
                                  const RenderResult& r, const TileSize& tile, double write_ms) {
    const RenderStats& st = r.stats;
    const double mrays = st.render_ms > 0 ? st.rays.total() / (st.render_ms * 1000.0) : 0.0;
    nlohmann::ordered_json j = {
        {"scene", scene.name},
        {"device", st.device_name},
        {"width", r.image.width},
        {"height", r.image.height},
        {"max_depth", o.frame.max_depth ? o.frame.max_depth : scene.settings.max_depth},
        {"samples", o.frame.samples ? o.frame.samples : scene.settings.samples},
        {"accel", to_string(o.commit.accel)},
        {"traversal", to_string(o.commit.traversal)},
        {"precision", to_string(o.commit.accuracy.precision)},
        {"triangle_test", to_string(o.commit.accuracy.triangle_test)},
        {"sphere_test", to_string(o.commit.accuracy.sphere_test)},
        {"self_intersection", to_string(o.commit.accuracy.self_intersection)},
        // The builder named by --tree only when it made the tree; "file" for --load-tree, "none" without a tree.
        {"tree", !a.load_tree.empty() ? std::string("file")
                 : st.tree_stats      ? a.tree
                 : st.bvh_stats       ? std::string("bvh")
                                      : std::string("none")},
        {"tree_file", a.load_tree.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(a.load_tree)},
        {"tree_loaded", st.tree_loaded},
        {"features", st.features.names()},
        {"build_ms", st.build_ms},
        {"compile_ms", st.compile_ms},
        {"upload_ms", st.upload_ms},
        {"kernel_cache_hit", st.opencl.kernel_cache_hit},
        {"kernel_options", st.opencl.kernel_options},
        {"launches", st.opencl.launches},
        {"render_ms", st.render_ms},
        {"write_ms", write_ms},  // encoding and writing the image and id map
        {"rays", {{"camera", st.rays.camera}, {"shadow", st.rays.shadow}, {"secondary", st.rays.secondary},
                  {"total", st.rays.total()}}},
        {"mrays_per_s", mrays}};
    if (st.tree_stats) j["tree_stats"] = tree_stats_json(*st.tree_stats);
    if (st.bvh_stats) j["bvh_stats"] = bvh_stats_json(*st.bvh_stats);
    if (st.refits) j["refits"] = st.refits;
    if (!st.device_shares.empty()) {
        j["tile"] = {{"width", tile.width}, {"height", tile.height}};
        nlohmann::ordered_json shares = nlohmann::ordered_json::array();
        for (const DeviceShare& d : st.device_shares)
            shares.push_back({{"device", d.device_name},
                              {"tiles", d.tiles},
                              {"pixels", d.pixels},
                              {"busy_ms", d.busy_ms},
                              {"rays", {{"camera", d.rays.camera}, {"shadow", d.rays.shadow},
                                        {"secondary", d.rays.secondary}, {"total", d.rays.total()}}}});
        j["device_shares"] = shares;
    }
    if (!st.opencl.kernel_resources.empty()) {
        // As the OpenCL implementation reports them (PoCL: 0 private bytes), with kdrt's stack estimate.
        nlohmann::ordered_json kernels = nlohmann::ordered_json::array();
        for (const KernelResources& k : st.opencl.kernel_resources)
            kernels.push_back({{"kernel", k.kernel},
                               {"private_bytes", k.private_bytes},
                               {"local_bytes", k.local_bytes},
                               {"work_group_size", k.work_group_size},
                               {"preferred_multiple", k.preferred_multiple}});
        j["kernel_resources"] = kernels;
        j["traversal_stack_bytes"] = st.opencl.traversal_stack_bytes;
    }
    if (!st.opencl.command_times.empty()) {
        nlohmann::ordered_json commands = nlohmann::ordered_json::array();
        for (const CommandTime& c : st.opencl.command_times)
            commands.push_back({{"command", c.command}, {"level", c.level}, {"count", c.count},
                                {"device_ms", c.device_ms}});
        j["command_times"] = commands;
        j["device_busy_ms"] = st.opencl.device_busy_ms;
    }
    return j;
}

void print_stats(const Args& a, nlohmann::ordered_json j, int frame) {
    if (a.frames > 1) j["frame"] = frame;
    std::cout << j.dump() << "\n";
}

}  // namespace kdrt::cli
