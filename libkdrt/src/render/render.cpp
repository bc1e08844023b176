#include "common/atomic_file.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device_handle.h>
#include <kdrt/error.h>
#include <kdrt/render.h>

#include <bit>

namespace kdrt {

const char* to_string(Traversal t) {
    switch (t) {
        case Traversal::None: return "none";
        case Traversal::Restart: return "restart";
        case Traversal::Ropes: return "ropes";
        case Traversal::Stack: return "stack";
    }
    return "?";
}

Traversal traversal_from_string(const std::string& name) {
    for (Traversal t : {Traversal::None, Traversal::Restart, Traversal::Ropes, Traversal::Stack})
        if (name == to_string(t)) return t;
    throw Error(ErrorCode::InvalidArgument, "unknown traversal '" + name + "' (expected none, restart, ropes or stack)");
}

const char* to_string(Precision p) { return p == Precision::Double ? "double" : "float"; }

const char* to_string(TriangleTest t) { return t == TriangleTest::MollerTrumbore ? "moller" : "watertight"; }

TriangleTest triangle_test_from_string(const std::string& name) {
    if (name == "watertight") return TriangleTest::Watertight;
    if (name == "moller") return TriangleTest::MollerTrumbore;
    throw Error(ErrorCode::InvalidArgument, "unknown triangle test '" + name + "' (expected watertight or moller)");
}

const char* to_string(SphereTest t) { return t == SphereTest::Textbook ? "textbook" : "careful"; }

SphereTest sphere_test_from_string(const std::string& name) {
    if (name == "careful") return SphereTest::Careful;
    if (name == "textbook") return SphereTest::Textbook;
    throw Error(ErrorCode::InvalidArgument, "unknown sphere test '" + name + "' (expected careful or textbook)");
}

const char* to_string(SelfIntersection s) { return s == SelfIntersection::FixedEpsilon ? "fixed" : "scale-aware"; }

SelfIntersection self_intersection_from_string(const std::string& name) {
    if (name == "scale-aware") return SelfIntersection::ScaleAware;
    if (name == "fixed") return SelfIntersection::FixedEpsilon;
    throw Error(ErrorCode::InvalidArgument,
                "unknown self-intersection handling '" + name + "' (expected scale-aware or fixed)");
}

const char* to_string(Schedule s) { return s == Schedule::Plain ? "plain" : "persistent"; }

Schedule schedule_from_string(const std::string& name) {
    if (name == "persistent") return Schedule::Persistent;
    if (name == "plain") return Schedule::Plain;
    throw Error(ErrorCode::InvalidArgument, "unknown schedule '" + name + "' (expected persistent or plain)");
}

const char* to_string(RayOrder o) {
    switch (o) {
        case RayOrder::Rows: return "rows";
        case RayOrder::Tiles: return "tiles";
        case RayOrder::Morton: return "morton";
    }
    return "?";
}

RayOrder ray_order_from_string(const std::string& name) {
    for (RayOrder o : {RayOrder::Rows, RayOrder::Tiles, RayOrder::Morton})
        if (name == to_string(o)) return o;
    throw Error(ErrorCode::InvalidArgument, "unknown ray order '" + name + "' (expected rows, tiles or morton)");
}

Precision precision_from_string(const std::string& name) {
    if (name == "float") return Precision::Float;
    if (name == "double") return Precision::Double;
    throw Error(ErrorCode::InvalidArgument, "unknown precision '" + name + "' (expected float or double)");
}

// One call: open the device, commit, render one frame (which reports the
// commit's build, compile and upload).
RenderResult render(const Scene& scene, const RenderOptions& options) {
    const Device device = Device::open(options.device);
    return CommittedScene::commit(device, scene, options).render(options);
}

void write_id_map(const std::filesystem::path& path, const RenderResult& result) {
    if (result.ids.empty() || result.ids.size() != result.hit_t.size())
        throw Error(ErrorCode::InvalidArgument, "write_id_map: the render has no id map (want_ids was off)");
    std::vector<unsigned char> bytes;
    bytes.reserve(result.ids.size() * 8);
    auto put = [&](std::uint32_t v) {
        for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<unsigned char>(v >> (8 * i)));
    };
    for (std::int32_t id : result.ids) put(static_cast<std::uint32_t>(id));
    for (float t : result.hit_t) put(std::bit_cast<std::uint32_t>(t));
    detail::write_file_atomically(path, bytes);
}

}  // namespace kdrt
