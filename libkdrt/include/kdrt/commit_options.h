// What is fixed when a scene is committed to a device (CommittedScene::commit,
// MultiDeviceScene::commit, the one-call render()): the traversal, the tree
// and where it comes from, the accuracy knobs the kernels are specialised
// for, the kernel cache. Frames change none of it (kdrt/frame_options.h).
#pragma once

#include <kdrt/bvh_config.h>
#include <kdrt/export.h>
#include <kdrt/kd_tree.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace kdrt {

// The acceleration structure: a kd-tree (the study's) or a bounding volume
// hierarchy (kdrt/bvh_config.h). CommitOptions' default is the BVH
// (docs/API.md says why); the kd-tree is the one with the restart, ropes and
// short-stack traversals.
enum class Accel { KdTree, Bvh };
// How the structure is walked. A kd-tree has all five; a BVH has Stack (its
// stack traversal, nearest first for closest hits) and None.
enum class Traversal { None, Restart, Ropes, Stack, ShortStack };
enum class Precision { Float, Double };
// Accuracy knobs: each trades robustness for speed (BENCHMARKS.md says how much).
enum class TriangleTest { Watertight, MollerTrumbore };  // Woop et al. 2013 | Moller and Trumbore 1997
enum class SphereTest { Careful, Textbook };             // Haines et al. 2019 | the quadratic formula
enum class SelfIntersection { ScaleAware, FixedEpsilon };  // relative offset + self-exclusion | absolute offset

KDRT_API const char* to_string(Accel a);
KDRT_API Accel accel_from_string(const std::string& name);  // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(Traversal t);
KDRT_API Traversal traversal_from_string(const std::string& name);  // names: kdrt/enum_names.h; throws
// Whether a BVH can be walked with `t`: Stack and None; the others are the kd-tree's.
KDRT_API bool bvh_has_traversal(Traversal t);
KDRT_API const char* to_string(Precision p);
KDRT_API Precision precision_from_string(const std::string& name);  // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(TriangleTest t);
KDRT_API TriangleTest triangle_test_from_string(const std::string& name);   // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(SphereTest t);
KDRT_API SphereTest sphere_test_from_string(const std::string& name);       // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(SelfIntersection s);
KDRT_API SelfIntersection self_intersection_from_string(const std::string& name);  // names: kdrt/enum_names.h; throws

// How intersections are computed; the defaults are the robust choices.
struct AccuracyOptions {
    Precision precision = Precision::Float;       // Double needs fp64 on OpenCL devices
    TriangleTest triangle_test = TriangleTest::Watertight;
    SphereTest sphere_test = SphereTest::Careful;
    SelfIntersection self_intersection = SelfIntersection::ScaleAware;
    double fixed_epsilon = 1e-4;                  // SelfIntersection::FixedEpsilon: offset in scene units, > 0
};

// Where the structure (a BVH or kd-tree, as CommitOptions::accel says) comes
// from besides a fresh build, and where it goes. Only Traversal::Ropes gets
// ropes, built after loading a rope-less kd-tree; `save` writes the structure
// as used; the cache keeps kd-trees without ropes and removes its own
// temporary files left by killed saves (> 10 min old).
struct TreeFiles {
    std::optional<std::filesystem::path> load;       // a file of the structure for this geometry
    std::optional<std::filesystem::path> save;       // write the structure used here
    std::optional<std::filesystem::path> cache_dir;  // directory of structures, found by geometry and builder
    // A kd-tree built in memory (build_scene_tree, build_kd_tree) for this
    // scene's geometry, with Accel::KdTree; checked like a loaded one. Takes
    // precedence over `load`.
    std::shared_ptr<const KdTree> in_memory;
};

struct CommitOptions {
    Accel accel = Accel::Bvh;
    Traversal traversal = Traversal::Stack;
    KdBuildConfig tree;          // Accel::KdTree: builder and its parameters
    BvhBuildConfig bvh;          // Accel::Bvh: builder and its parameters
    bool build_tree = false;     // build the structure even for Traversal::None (statistics, saving)
    AccuracyOptions accuracy;
    bool all_features = false;   // ignore the scene's feature set: the generic kernels (for comparison)
    TreeFiles tree_files;
    std::optional<std::filesystem::path> kernel_cache_dir;  // OpenCL: compiled programs; default: the user's cache dir
    double max_query_launch_ms = 200.0;  // OpenCL ray queries: split a batch so that no launch runs longer (watchdogs; 0: no limit)
    // Called with the finished fraction in [0, 1] of the structure's build, then
    // of the upload, from the calling thread (a build calls it from one builder
    // thread at a time, unless tree.progress or bvh.progress is set); returning false
    // cancels: the commit then throws kdrt::Error(Cancelled) soon after
    // (within ~100 ms), having joined its workers and written nothing.
    std::function<bool(double)> progress;
};

}  // namespace kdrt
