// to_string and the *_from_string functions of the option enums, all read
// from the tables in <kdrt/enum_names.h>.
#include <kdrt/enum_names.h>

namespace kdrt {

static_assert(enum_table_in_order<Accel>() && enum_table_in_order<Traversal>() && enum_table_in_order<KdBuilderKind>() &&
              enum_table_in_order<Precision>() && enum_table_in_order<Schedule>() &&
              enum_table_in_order<TriangleTest>() && enum_table_in_order<SphereTest>() &&
              enum_table_in_order<SelfIntersection>() && enum_table_in_order<RayOrder>());

const char* to_string(Accel a) { return enum_name(a); }
const char* to_string(Traversal t) { return enum_name(t); }
const char* to_string(KdBuilderKind kind) { return enum_name(kind); }
const char* to_string(Precision p) { return enum_name(p); }
const char* to_string(Schedule s) { return enum_name(s); }
const char* to_string(TriangleTest t) { return enum_name(t); }
const char* to_string(SphereTest t) { return enum_name(t); }
const char* to_string(SelfIntersection s) { return enum_name(s); }
const char* to_string(RayOrder o) { return enum_name(o); }

Accel accel_from_string(const std::string& name) { return enum_from_name<Accel>(name); }
Traversal traversal_from_string(const std::string& name) { return enum_from_name<Traversal>(name); }
KdBuilderKind kd_builder_from_string(const std::string& name) { return enum_from_name<KdBuilderKind>(name); }
Precision precision_from_string(const std::string& name) { return enum_from_name<Precision>(name); }
Schedule schedule_from_string(const std::string& name) { return enum_from_name<Schedule>(name); }
TriangleTest triangle_test_from_string(const std::string& name) { return enum_from_name<TriangleTest>(name); }
SphereTest sphere_test_from_string(const std::string& name) { return enum_from_name<SphereTest>(name); }
SelfIntersection self_intersection_from_string(const std::string& name) {
    return enum_from_name<SelfIntersection>(name);
}
RayOrder ray_order_from_string(const std::string& name) { return enum_from_name<RayOrder>(name); }

}  // namespace kdrt
