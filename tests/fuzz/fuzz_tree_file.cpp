// libFuzzer target: kd-tree files through kdrt::deserialize_kd_tree, with the
// checksum recomputed (tree_file_input.h): the checks behind it (node links,
// leaf ranges, ropes, bounds) are what gets fuzzed.
#include "tree_file_input.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree_io.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const TreeFileInput in = tree_file_input(data, size, {108, 116, 124});
    try {
        kdrt::deserialize_kd_tree(in.bytes.data(), in.bytes.size(), in.fingerprint, "fuzz.kdtree");
    } catch (const kdrt::Error&) {
    }
    return 0;
}
