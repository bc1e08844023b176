// kdrt-bench accuracy: what each step of accuracy costs in time. Every knob
// setting (precision, triangle and sphere tests, self-intersection handling,
// ray depth, samples per pixel, tree builder) is timed and compared with a
// high-accuracy reference: the C++ reference in double precision, watertight,
// careful spheres, scale-aware offsets, full depth, many samples.
#pragma once

#include "scene_set.h"

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct AccuracyConfig {
    std::vector<NamedScene> scenes;
    std::vector<std::string> devices;  // "cpu", "opencl:0", ...
    int width = 250, height = 250;
    int runs = 3;               // timed runs per setting after one warm-up; the median is reported
    int reference_samples = 16; // samples per pixel of the reference
    std::filesystem::path out;  // accuracy.csv, accuracy.md, accuracy.png
};

// Runs the study and writes the outputs; returns the process exit code.
int run_accuracy(const AccuracyConfig& config);

}  // namespace kdrt::bench
