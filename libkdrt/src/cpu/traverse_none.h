// Traversal "none": every object, in id order (the study's "no tree").
#pragma once

#include "cpu/ray.h"

#include <cstdint>
#include <vector>

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Real, class Visit>
void traverse_none(const std::vector<std::uint32_t>& all_ids, const Ray<Real>&, Real, Visit&& visit) {
    visit(all_ids.data(), static_cast<std::uint32_t>(all_ids.size()));
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
