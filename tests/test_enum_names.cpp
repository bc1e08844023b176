// The option enums' name tables (<kdrt/enum_names.h>): every value has one
// distinct name, to_string and *_from_string agree with the table, and an
// unknown name is refused with a message that lists the accepted ones.
#include <catch2/catch.hpp>

#include <kdrt/enum_names.h>

#include <set>
#include <string>

using namespace kdrt;

namespace {

template <class E, class FromString>
void check_table(FromString from_string) {
    std::set<std::string> seen;
    for (const EnumName<E>& n : enum_names<E>()) {
        INFO(EnumTable<E>::kind << " " << n.name);
        CHECK(seen.insert(n.name).second);
        CHECK(std::string(n.description).size() > 0);
        CHECK(std::string(to_string(n.value)) == n.name);
        CHECK(from_string(n.name) == n.value);
    }
    try {
        from_string("no-such-name");
        FAIL("an unknown " << EnumTable<E>::kind << " was accepted");
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::InvalidArgument);
        const std::string message = e.what();
        CHECK(message.find("no-such-name") != std::string::npos);
        CHECK(message.find(EnumTable<E>::kind) != std::string::npos);
        for (const EnumName<E>& n : enum_names<E>()) CHECK(message.find(n.name) != std::string::npos);
    }
    CHECK_FALSE(find_enum<E>("").has_value());
}

}  // namespace

TEST_CASE("enum name tables agree with to_string and from_string", "[enum]") {
    check_table<Traversal>(traversal_from_string);
    check_table<KdBuilderKind>(kd_builder_from_string);
    check_table<Precision>(precision_from_string);
    check_table<Schedule>(schedule_from_string);
    check_table<TriangleTest>(triangle_test_from_string);
    check_table<SphereTest>(sphere_test_from_string);
    check_table<SelfIntersection>(self_intersection_from_string);
    check_table<RayOrder>(ray_order_from_string);
}

TEST_CASE("enum name lists read like prose", "[enum]") {
    CHECK(enum_name_list<Traversal>() == "none, restart, ropes, stack or short-stack");
    CHECK(enum_name_list<Precision>() == "float or double");
    CHECK(std::string(enum_name(static_cast<Traversal>(99))) == "?");
}
