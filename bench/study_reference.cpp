#include "study_reference.h"

#include "report.h"
#include "scene_set.h"

#include <limits>

namespace kdrt::bench {

const std::vector<StudyRow>& study_rows() {
    static const std::vector<StudyRow> rows{
        {"study CPU none", {252, 13138, 74844, 188, 720000}, {false, false, false, false, true}},
        {"study CPU basic (restart)", {133, 15593, 251, 170, 10910}, {false, false, false, false, false}},
        {"study CPU neighbour (ropes)", {131, 15443, 250, 175, 10760}, {false, false, false, false, false}},
        {"study GPU none", {590, 1010, 2660, 610, 15000}, {false, false, false, false, true}},
        {"study GPU basic (restart)", {603, 1480, 619, 610, 4730}, {false, false, false, false, false}},
        {"study GPU neighbour (ropes)", {612, 1483, 620, 607, 4470}, {false, false, false, false, false}},
    };
    return rows;
}

namespace {

int scene_index(const std::string& scene) {
    const auto& names = study_scene_names();
    for (std::size_t i = 0; i < names.size(); ++i)
        if (names[i] == scene) return static_cast<int>(i);
    return -1;
}

}  // namespace

std::string study_cell(const StudyRow& row, const std::string& scene) {
    const int i = scene_index(scene);
    if (i < 0) return "-";
    const std::string v = fmt(row.ms[static_cast<std::size_t>(i)], 0);
    return row.lower_bound[static_cast<std::size_t>(i)] ? "> " + v : v;
}

double study_ms(const StudyRow& row, const std::string& scene) {
    const int i = scene_index(scene);
    return i < 0 ? std::numeric_limits<double>::quiet_NaN() : row.ms[static_cast<std::size_t>(i)];
}

}  // namespace kdrt::bench
