// compare_id_maps: ties and silhouettes are forgiven, nothing else.
#include <kdrt/id_map.h>

#include <catch2/catch.hpp>

#include <vector>

TEST_CASE("id maps: identical, ties, silhouettes and real disagreements", "[idmap]") {
    // 4x3: object 1 on the left half, object 2 on the right, background (-1) in the last row.
    const std::vector<std::int32_t> ref = {1, 1, 2, 2, 1, 1, 2, 2, -1, -1, -1, -1};
    const std::vector<float> t = {5, 5, 6, 6, 5, 5, 6, 6, 0, 0, 0, 0};
    CHECK(kdrt::compare_id_maps(4, 3, ref, t, ref, t).summary() == "ok, identical");

    // A silhouette pixel (its neighbours see another object) may flip.
    std::vector<std::int32_t> ids = ref;
    std::vector<float> ids_t = t;
    ids[1] = 2;
    ids_t[1] = 6;
    kdrt::IdMapComparison c = kdrt::compare_id_maps(4, 3, ref, t, ids, ids_t);
    CHECK(c.ok());
    CHECK(c.edges == 1);

    // A tie: another object at the same distance (to 1e-4).
    std::vector<std::int32_t> tie_ids = ref;
    std::vector<float> tie_t = t;
    tie_ids[0] = 7;
    tie_t[0] = 5.0002f;
    c = kdrt::compare_id_maps(4, 3, ref, t, tie_ids, tie_t);
    CHECK(c.ok());
    CHECK(c.ties == 1);

    // A pixel inside a uniform region hitting something else far away: a failure.
    const std::vector<std::int32_t> big = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
    const std::vector<float> bt(12, 5.0f);
    std::vector<std::int32_t> wrong = big;
    wrong[5] = -1;
    c = kdrt::compare_id_maps(4, 3, big, bt, wrong, bt);
    CHECK_FALSE(c.ok());
    CHECK(c.unexplained == 1);

    // Maps of the wrong size explain nothing.
    CHECK_FALSE(kdrt::compare_id_maps(4, 3, ref, t, std::vector<std::int32_t>(3), std::vector<float>(3)).ok());
}
