// The names of the option enums, one table per enum: what to_string and the
// *_from_string functions, the command line and the reports all read, so a
// name is spelled in exactly one place.
#pragma once

#include <kdrt/commit_options.h>
#include <kdrt/error.h>
#include <kdrt/frame_options.h>
#include <kdrt/kd_tree.h>

#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace kdrt {

template <class E>
struct EnumName {
    E value;
    const char* name;         // in options, files and reports
    const char* description;  // a few words for help texts
};

// EnumTable<E>::kind names the choice in messages; EnumTable<E>::names lists
// every value once, in declaration order (checked where to_string is defined).
template <class E>
struct EnumTable;

template <>
struct EnumTable<Accel> {
    static constexpr const char* kind = "acceleration structure";
    static constexpr EnumName<Accel> names[] = {
        {Accel::KdTree, "kd", "kd-tree"},
        {Accel::Bvh, "bvh", "bounding volume hierarchy, eight children per node"},
    };
};

template <>
struct EnumTable<Traversal> {
    static constexpr const char* kind = "traversal";
    static constexpr EnumName<Traversal> names[] = {
        {Traversal::None, "none", "no tree: every object"},
        {Traversal::Restart, "restart", "kd-restart, Foley and Sugerman 2005"},
        {Traversal::Ropes, "ropes", "neighbour links, Havran et al. 1998"},
        {Traversal::Stack, "stack", "a stack of far children"},
        {Traversal::ShortStack, "short-stack", "a few stack entries, restart and push-down, Horn et al. 2007"},
    };
};

template <>
struct EnumTable<KdBuilderKind> {
    static constexpr const char* kind = "kd-tree builder";
    static constexpr EnumName<KdBuilderKind> names[] = {
        {KdBuilderKind::Median, "median", "the study's spatial median"},
        {KdBuilderKind::Sah, "sah", "binned SAH, parallel"},
        {KdBuilderKind::SahExact, "sah-exact", "the exact SAH sweep, serial"},
    };
};

template <>
struct EnumTable<Precision> {
    static constexpr const char* kind = "precision";
    static constexpr EnumName<Precision> names[] = {
        {Precision::Float, "float", "single precision"},
        {Precision::Double, "double", "needs fp64 on OpenCL devices"},
    };
};

template <>
struct EnumTable<Schedule> {
    static constexpr const char* kind = "schedule";
    static constexpr EnumName<Schedule> names[] = {
        {Schedule::Persistent, "persistent",
         "persistent threads, Aila and Laine 2009; a CPU device's work-items trace whole ray trees"},
        {Schedule::Plain, "plain", "one work-item per ray"},
        {Schedule::Wavefront, "wavefront", "persistent threads, a ray queue per bounce level on every device"},
    };
};

template <>
struct EnumTable<TriangleTest> {
    static constexpr const char* kind = "triangle test";
    static constexpr EnumName<TriangleTest> names[] = {
        {TriangleTest::Watertight, "watertight", "Woop et al. 2013"},
        {TriangleTest::MollerTrumbore, "moller", "Moller-Trumbore 1997"},
    };
};

template <>
struct EnumTable<SphereTest> {
    static constexpr const char* kind = "sphere test";
    static constexpr EnumName<SphereTest> names[] = {
        {SphereTest::Careful, "careful", "Ray Tracing Gems ch. 7"},
        {SphereTest::Textbook, "textbook", "the quadratic formula"},
    };
};

template <>
struct EnumTable<SelfIntersection> {
    static constexpr const char* kind = "self-intersection handling";
    static constexpr EnumName<SelfIntersection> names[] = {
        {SelfIntersection::ScaleAware, "scale-aware", "relative offset + self-exclusion"},
        {SelfIntersection::FixedEpsilon, "fixed", "an absolute offset"},
    };
};

template <>
struct EnumTable<RayOrder> {
    static constexpr const char* kind = "ray order";
    static constexpr EnumName<RayOrder> names[] = {
        {RayOrder::Rows, "rows", "row by row"},
        {RayOrder::Tiles, "tiles", "8x8 screen tiles"},
        {RayOrder::Morton, "morton", "a Morton curve"},
    };
};

template <class E>
constexpr std::span<const EnumName<E>> enum_names() {
    return EnumTable<E>::names;
}

// True when the table holds value i at row i for every row (the declaration order).
template <class E>
constexpr bool enum_table_in_order() {
    int i = 0;
    for (const EnumName<E>& n : enum_names<E>())
        if (static_cast<int>(n.value) != i++) return false;
    return true;
}

// The value's name; "?" for a value outside the table (a cast integer).
template <class E>
constexpr const char* enum_name(E value) {
    for (const EnumName<E>& n : enum_names<E>())
        if (n.value == value) return n.name;
    return "?";
}

template <class E>
constexpr std::optional<E> find_enum(std::string_view name) {
    for (const EnumName<E>& n : enum_names<E>())
        if (name == n.name) return n.value;
    return std::nullopt;
}

// "a, b or c": the accepted names, for messages.
template <class E>
std::string enum_name_list() {
    const auto names = enum_names<E>();
    std::string list;
    for (std::size_t i = 0; i < names.size(); ++i) {
        if (i > 0) list += i + 1 == names.size() ? " or " : ", ";
        list += names[i].name;
    }
    return list;
}

// The value named `name`; kdrt::Error(InvalidArgument) naming the accepted ones otherwise.
template <class E>
E enum_from_name(std::string_view name) {
    if (const std::optional<E> value = find_enum<E>(name)) return *value;
    throw Error(ErrorCode::InvalidArgument, std::string("unknown ") + EnumTable<E>::kind + " '" + std::string(name) +
                                                "' (expected " + enum_name_list<E>() + ")");
}

}  // namespace kdrt
