// The 2016 study's table (issue 5), in ms: CPU i7-2670QM, GPU GeForce GT 540M
// (CUDA), 500x500, kd depth 10, ray depth 15. Its scenes are only described
// in words, so ours follow the descriptions but are not identical: context,
// not a yardstick.
#pragma once

#include <string>
#include <vector>

namespace kdrt::bench {

// The study's kd-tree depth: its median builder's trees are rows "median-10".
inline constexpr int kStudyMedianDepth = 10;

struct StudyRow {
    std::string label;  // "study CPU none", ...
    // Per study scene (study_scene_names() order); a figure and whether it is a lower bound ("> 720000").
    std::vector<double> ms;
    std::vector<bool> lower_bound;
};

const std::vector<StudyRow>& study_rows();

// The study's figure for a scene name, formatted ("> 720000"); "-" for other scenes.
std::string study_cell(const StudyRow& row, const std::string& scene);
// The figure for a scene, NaN for other scenes.
double study_ms(const StudyRow& row, const std::string& scene);

}  // namespace kdrt::bench
