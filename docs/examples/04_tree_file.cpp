// Builds a scene's kd-tree once, saves it, and commits the scene again from
// the file: the second commit loads the tree instead of building it.
#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/kd_tree_io.h>
#include <kdrt/scene_loader.h>

#include <cstdio>

int main(int argc, char** argv) {
    kdrt::Scene scene = kdrt::load_scene(argc > 1 ? argv[1] : "scenes/ball-o-calypse.json");
    kdrt::Device device = kdrt::Device::open();

    // First run: build, then save the tree with the fingerprint of the
    // geometry it belongs to (a file for other geometry is refused).
    kdrt::CommitOptions kd;
    kd.accel = kdrt::Accel::KdTree;  // the default is the BVH, whose files are TreeFiles' too
    kdrt::CommittedScene first = kdrt::CommittedScene::commit(device, scene, kd);
    kdrt::save_kd_tree("04_scene.kdtree", *first.tree(), first.geometry_fingerprint());
    std::printf("built in %.1f ms, %zu nodes\n", first.stats().build_ms, first.tree()->nodes.size());

    // Later runs: load it (checked against the scene) instead of building.
    kdrt::CommitOptions options = kd;
    options.tree_files.load = "04_scene.kdtree";
    kdrt::CommittedScene second = kdrt::CommittedScene::commit(device, scene, options);
    std::printf("second commit: %llu build(s), %llu tree load(s)\n",
                static_cast<unsigned long long>(second.stats().builds),
                static_cast<unsigned long long>(second.stats().tree_loads));

    // Or without a commit: build_scene_tree() and load_kd_tree() directly.
    kdrt::KdTree tree = kdrt::load_kd_tree("04_scene.kdtree", kdrt::geometry_fingerprint(scene));
    bool same = tree == kdrt::build_scene_tree(scene);
    std::printf("the file holds the tree a build makes: %s\n", same ? "yes" : "no");
    return second.stats().builds == 0 && same ? 0 : 1;
}
