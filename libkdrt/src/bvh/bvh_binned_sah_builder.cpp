// Binned SAH BVH builder, after I. Wald, "On fast Construction of SAH-based
// Bounding Volume Hierarchies" (IRT 2007), as Embree builds its BVHs:
//  - each object is one reference (its box rounded outward to floats), in
//    exactly one leaf: no spatial splits;
//  - a node's split is looked for among bins - 1 planes per axis, evenly
//    spaced over the extent of the objects' centroids; one pass over the
//    objects counts them and grows each bin's box, a sweep from each side
//    gives every plane's SAH cost (Goldsmith-Salmon, MacDonald-Booth);
//  - a node becomes a leaf when it holds at most max_leaf_size objects and no
//    split is cheaper than testing them all; a node whose centroids all
//    coincide is cut in two halves of its list (Embree's fallback);
//  - the depth stays within kBvhMaxDepth: a node too deep for its objects to
//    reach leaves by SAH splits is cut in halves, which keeps every leaf within it;
//  - parallel over subtrees (the second child of a large node is a task of
//    its own, built into a fragment that is copied into place at the end) and,
//    for large nodes, over objects: binning and the bounds of a node's children
//    are minima, maxima and integer counts, exact in any order, and the
//    partition of a large node scatters fixed-size blocks to places counted in
//    block order. So the BVH is the same, bit for bit, for any thread count.
// Changed from Wald's paper: the leaf cost counts triangles in blocks of
// leaf_block (the cpu device tests a leaf's triangles 4 or 8 at a time, and
// Embree counts its Triangle4 leaves so), spheres apart from triangles.
#include "bvh/bvh_boxes.h"
#include "bvh/bvh_build.h"
#include "common/parallel_chunks.h"
#include "common/tsan_fork_join.h"

#include <kdrt/error.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace kdrt {

namespace {

typedef float F4 __attribute__((vector_size(16)));
typedef std::int32_t I4 __attribute__((vector_size(16)));

inline F4 vmin(F4 a, F4 b) { return a < b ? a : b; }
inline F4 vmax(F4 a, F4 b) { return a > b ? a : b; }
constexpr float kInf = std::numeric_limits<float>::infinity();

// An object's box and id, 32 bytes: two aligned vector loads.
struct alignas(16) PrimRef {
    float lo[3];
    std::uint32_t id;  // in the lower box's fourth lane, masked off when loaded
    float hi[3];
    float zero;
};

inline F4 load_lo(const PrimRef& r) {
    I4 v;
    std::memcpy(&v, &r, sizeof v);
    v &= I4{-1, -1, -1, 0};  // the id's bits would be a denormal float: no arithmetic on them
    return std::bit_cast<F4>(v);
}
inline F4 load_hi(const PrimRef& r) {
    F4 v;
    std::memcpy(&v, &r.hi, sizeof v);
    return v;
}
// The centroid, without overflow for boxes near the float range's ends.
inline F4 centroid(F4 lo, F4 hi) { return lo * 0.5f + hi * 0.5f; }

// A node's objects: the union of their boxes and the bounds of their centroids.
struct Info {
    F4 lo = {kInf, kInf, kInf, kInf}, hi = {-kInf, -kInf, -kInf, -kInf};
    F4 clo = {kInf, kInf, kInf, kInf}, chi = {-kInf, -kInf, -kInf, -kInf};

    void add(F4 l, F4 h) {
        lo = vmin(lo, l);
        hi = vmax(hi, h);
        const F4 c = centroid(l, h);
        clo = vmin(clo, c);
        chi = vmax(chi, c);
    }
    void add(const PrimRef& r) { add(load_lo(r), load_hi(r)); }
    void merge(const Info& o) {
        lo = vmin(lo, o.lo);
        hi = vmax(hi, o.hi);
        clo = vmin(clo, o.clo);
        chi = vmax(chi, o.chi);
    }
};

// Nodes at least this large are binned and partitioned in parallel.
constexpr std::size_t kParallelObjects = std::size_t{1} << 15;
// The block of a parallel partition: a fixed size, so the result never depends on the thread count.
constexpr std::size_t kBlock = std::size_t{1} << 13;
// Nodes at least this large build their second child as a task of its own.
constexpr std::size_t kParallelSubtree = std::size_t{1} << 12;
constexpr int kMaxBins = 256;
// Objects per bin from which binning takes two sets of bins (Bins::add_pairs).
constexpr int kPairedBinsPerBin = 4;
constexpr int kMinBins = 8;

// Where a centroid falls: bin = (c - base) * scale on each axis, clamped.
struct BinMap {
    F4 base{}, scale{};
    int bins = 0;
    bool axis[3] = {false, false, false};  // the centroids spread on it

    BinMap(const Info& info, int bin_count) : base(info.clo), bins(bin_count) {
        const F4 extent = info.chi - info.clo;
        for (int a = 0; a < 3; ++a) {
            // 1 - 2^-16 keeps the largest centroid inside the last bin.
            const float s = extent[a] > 0.0f ? static_cast<float>(bins) * 0.99998474f / extent[a] : 0.0f;
            axis[a] = std::isfinite(s) && s > 0.0f;
            scale[a] = axis[a] ? s : 0.0f;
        }
    }
    I4 bin(F4 c) const {
        F4 t = (c - base) * scale;
        const F4 zero{}, last = zero + static_cast<float>(bins - 1);
        t = t > zero ? t : zero;  // also for NaN
        t = t < last ? t : last;
        return __builtin_convertvector(t, I4);
    }
    I4 bin(const PrimRef& r) const { return bin(centroid(load_lo(r), load_hi(r))); }
};

// Per bin and axis: the union of the boxes of the objects whose centroid
// falls in that bin on that axis, their number and how many are spheres.
// Up to kLocalBins bins live in the object itself (most nodes are small: no
// allocation for them).
class Bins {
public:
    struct Bin {
        F4 lo[3], hi[3];                         // by axis
        std::uint32_t count[4], spheres[4];      // by axis, lane 3 unused
    };
    explicit Bins(int n) : bins(n) {
        if (n > kLocalBins) heap_.resize(static_cast<std::size_t>(n));
        bin_ = heap_.empty() ? local_ : heap_.data();
        for (int i = 0; i < n; ++i) {
            Bin& b = bin_[i];
            for (int a = 0; a < 3; ++a) {
                b.lo[a] = F4{} + kInf;
                b.hi[a] = F4{} - kInf;
            }
            for (int a = 0; a < 4; ++a) b.count[a] = b.spheres[a] = 0;
        }
    }
    Bins(const Bins&) = delete;
    Bins& operator=(const Bins&) = delete;

    const Bin& operator[](int i) const { return bin_[i]; }
    void merge(const Bins& o) {
        for (int i = 0; i < bins; ++i) {
            Bin& b = bin_[i];
            const Bin& c = o.bin_[i];
            for (int a = 0; a < 3; ++a) {
                b.lo[a] = vmin(b.lo[a], c.lo[a]);
                b.hi[a] = vmax(b.hi[a], c.hi[a]);
                b.count[a] += c.count[a];
                b.spheres[a] += c.spheres[a];
            }
        }
    }
    template <bool Spheres>
    void add(const PrimRef* refs, std::size_t n, const BinMap& map, std::uint32_t sphere_count) {
        for (std::size_t i = 0; i < n; ++i) add_one<Spheres>(refs[i], map, sphere_count);
    }
    // The even objects to these bins, the odd ones to `odd`, which the caller
    // merges: neighbouring objects often fall in the same bin, and with one
    // set each update would wait for the store of the one before.
    template <bool Spheres>
    void add_pairs(Bins& odd, const PrimRef* refs, std::size_t n, const BinMap& map, std::uint32_t sphere_count) {
        std::size_t i = 0;
        for (; i + 1 < n; i += 2) {
            add_one<Spheres>(refs[i], map, sphere_count);
            odd.add_one<Spheres>(refs[i + 1], map, sphere_count);
        }
        if (i < n) add_one<Spheres>(refs[i], map, sphere_count);
    }

    const int bins;

private:
    template <bool Spheres>
    void add_one(const PrimRef& r, const BinMap& map, std::uint32_t sphere_count) {
        const F4 l = load_lo(r), h = load_hi(r);
        const I4 k = map.bin(centroid(l, h));
        const std::uint32_t sphere = Spheres && r.id < sphere_count ? 1u : 0u;
        for (int a = 0; a < 3; ++a) {
            Bin& b = bin_[k[a]];
            b.lo[a] = vmin(b.lo[a], l);
            b.hi[a] = vmax(b.hi[a], h);
            ++b.count[a];
            if constexpr (Spheres) b.spheres[a] += sphere;
        }
    }

    static constexpr int kLocalBins = 32;
    Bin local_[kLocalBins];
    std::vector<Bin> heap_;
    Bin* bin_;
};

// The boxes of a run of bins, one per axis, and their half areas as one
// vector (lane a: axis a's box), with extents scaled by `unit` so that they
// stay well inside the float range whatever the scene's scale.
struct AxisBoxes {
    F4 lo[3] = {F4{} + kInf, F4{} + kInf, F4{} + kInf};
    F4 hi[3] = {F4{} - kInf, F4{} - kInf, F4{} - kInf};

    void add(const Bins::Bin& b) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = vmin(lo[a], b.lo[a]);
            hi[a] = vmax(hi[a], b.hi[a]);
        }
    }
    F4 half_areas(F4 unit) const {
        const F4 d0 = (hi[0] - lo[0]) * unit, d1 = (hi[1] - lo[1]) * unit, d2 = (hi[2] - lo[2]) * unit;
        const F4 x = {d0[0], d1[0], d2[0], 0.0f}, y = {d0[1], d1[1], d2[1], 0.0f}, z = {d0[2], d1[2], d2[2], 0.0f};
        return x * y + y * z + z * x;
    }
};

inline I4 load_counts(const std::uint32_t (&c)[4]) {
    I4 v;
    std::memcpy(&v, c, sizeof v);
    return v;
}

struct Split {
    int axis = -1;
    int bin = 0;  // the objects in bins below go to the first child
    // The children's area-weighted object costs, and the node's half area, in
    // the same units (half areas of boxes scaled by the node's largest extent).
    float cost = std::numeric_limits<float>::infinity();
    float node_area = 0.0f;
    bool valid() const { return axis >= 0; }
};

// A subtree built by a parallel task: its nodes, numbered from 0, and the
// fragments holding the children of some of them (links), built by tasks of
// their own. flatten() lays the fragments out one after the other.
struct Fragment {
    std::vector<Bvh2Node> nodes;
    struct Link {
        std::uint32_t node;  // nodes[node]'s children are fragment->nodes[first], [first + 1]
        std::unique_ptr<Fragment> fragment;
    };
    std::vector<Link> links;
};

void flatten(Fragment& root, std::vector<Bvh2Node>& out) {
    struct Placed {
        Fragment* fragment;
        std::uint32_t offset;
    };
    std::vector<Placed> placed;
    std::uint64_t total = 0;
    auto place = [&](auto& self, Fragment& f) -> void {
        placed.push_back({&f, static_cast<std::uint32_t>(total)});
        total += f.nodes.size();
        for (auto& link : f.links) self(self, *link.fragment);
    };
    place(place, root);
    out.resize(total);
    // Fragments were placed depth first: a fragment's links come after it, in order.
    auto copy = [&](std::size_t i) {
        const Fragment& f = *placed[i].fragment;
        const std::uint32_t offset = placed[i].offset;
        Bvh2Node* to = out.data() + offset;
        for (const Bvh2Node& n : f.nodes) {
            *to = n;
            if (!bvh2_is_leaf(n)) to->first += offset;
            ++to;
        }
    };
    {
        detail::TsanForkJoin tsan;
        tbb::parallel_for(std::size_t{0}, placed.size(), tsan.task(copy));
    }
    std::size_t next = 0;
    auto patch = [&](auto& self, const Fragment& f) -> void {
        const std::uint32_t offset = placed[next++].offset;
        for (const auto& link : f.links) {
            const std::uint32_t child_offset = placed[next].offset;
            out[offset + link.node].first = f.nodes[link.node].first + child_offset;
            self(self, *link.fragment);
        }
    };
    patch(patch, root);
}

class BinnedBuild {
public:
    BinnedBuild(const BvhBuildConfig& config, std::uint32_t sphere_count, PrimRef* buffer0, PrimRef* buffer1,
                std::uint32_t* leaf_objects, std::size_t total)
        : config_(config),
          sphere_count_(sphere_count),
          leaf_objects_(leaf_objects),
          total_(total),
          block_shift_(std::countr_zero(static_cast<unsigned>(config.leaf_block))) {
        buffers_[0] = buffer0;
        buffers_[1] = buffer1;
    }

    // Builds the subtree over refs [begin, end) of buffer `buf` (described by
    // `info`), its nodes below the root appended to `frag`; returns the root.
    Bvh2Node node(std::size_t begin, std::size_t end, const Info& info, int depth, int buf, Fragment& frag) {
        check_cancelled();
        const std::size_t n = end - begin;
        PrimRef* refs = buffers_[buf];
        // Past this depth a subtree of n objects cut in halves just reaches
        // its leaves at kBvhMaxDepth: from here on, halves only.
        const bool halves_only = depth + 1 + static_cast<int>(std::bit_width(n - 1)) > kBvhMaxDepth;
        const bool small = n <= static_cast<std::size_t>(config_.max_leaf_size);
        Split split;
        if (n > 1 && !halves_only) split = find_split(refs + begin, n, info);
        if (n == 1 || (small && (halves_only || !split.valid() ||
                                 static_cast<float>(config_.traversal_cost) * split.node_area + split.cost >=
                                     leaf_cost(refs + begin, n) * split.node_area)))
            return leaf(begin, end, info, refs);

        Info left, right;
        std::size_t mid;
        int child_buf = buf;
        if (split.valid()) {
            const BinMap map(info, bin_count(n));
            if (n >= kParallelObjects) {
                child_buf = 1 - buf;
                mid = partition_parallel(refs, buffers_[child_buf], begin, end, map, split, left, right);
            } else {
                mid = partition(refs, begin, end, map, split, left, right);
            }
        } else {
            mid = begin + n / 2;
            left = range_info(refs, begin, mid);
            right = range_info(refs, mid, end);
        }

        const auto pair = static_cast<std::uint32_t>(frag.nodes.size());
        frag.nodes.resize(frag.nodes.size() + 2);
        if (n >= kParallelSubtree) {
            auto second = std::make_unique<Fragment>();
            Bvh2Node a{}, b{};
            auto build_first = [&] { a = node(begin, mid, left, depth + 1, child_buf, frag); };
            auto build_second = [&] { b = node(mid, end, right, depth + 1, child_buf, *second); };
            {
                detail::TsanForkJoin tsan;
                tbb::parallel_invoke(tsan.task(build_first), tsan.task(build_second));
            }
            frag.nodes[pair] = a;
            frag.nodes[pair + 1] = b;
            if (!bvh2_is_leaf(b)) frag.links.push_back({pair + 1, std::move(second)});
        } else {
            const Bvh2Node a = node(begin, mid, left, depth + 1, child_buf, frag);
            frag.nodes[pair] = a;
            const Bvh2Node b = node(mid, end, right, depth + 1, child_buf, frag);
            frag.nodes[pair + 1] = b;
        }
        return make_node(info, pair, 0);
    }

    void check_cancelled() const {
        if (cancelled_.load(std::memory_order_relaxed)) throw Error(ErrorCode::Cancelled, "BVH build cancelled");
    }

private:
    static Bvh2Node make_node(const Info& info, std::uint32_t first, std::uint32_t count) {
        Bvh2Node n;
        for (int a = 0; a < 3; ++a) {
            n.lo[a] = info.lo[a];
            n.hi[a] = info.hi[a];
        }
        n.first = first;
        n.count = count;
        return n;
    }

    int bin_count(std::size_t n) const {
        return static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(config_.bins),
                                                       std::max<std::size_t>(n, kMinBins)));
    }

    // Objects' test cost: triangles in blocks of leaf_block (a power of
    // two), spheres one by one; a lane per axis.
    F4 weight(I4 count, I4 spheres) const {
        const I4 blocks = (count - spheres + (config_.leaf_block - 1)) >> block_shift_;
        return static_cast<float>(config_.intersection_cost) * __builtin_convertvector(blocks, F4) +
               static_cast<float>(config_.sphere_intersection_cost) * __builtin_convertvector(spheres, F4);
    }

    float leaf_cost(const PrimRef* refs, std::size_t n) const {
        std::int32_t spheres = 0;
        for (std::size_t i = 0; i < n; ++i) spheres += refs[i].id < sphere_count_ ? 1 : 0;
        return weight(I4{} + static_cast<std::int32_t>(n), I4{} + spheres)[0];
    }

    Split find_split(const PrimRef* refs, std::size_t n, const Info& info) const {
        const BinMap map(info, bin_count(n));
        Split best;
        if (!map.axis[0] && !map.axis[1] && !map.axis[2]) return best;
        Bins bins(map.bins);
        if (n >= kParallelObjects) {
            const std::size_t blocks = detail::chunk_count(n, kBlock);
            std::vector<std::unique_ptr<Bins>> parts(blocks);
            detail::for_each_chunk(
                n,
                [&](std::size_t c, std::size_t b, std::size_t e) {
                    parts[c] = std::make_unique<Bins>(map.bins);
                    add_to(*parts[c], refs + b, e - b, map);
                },
                kBlock);
            for (const auto& p : parts) bins.merge(*p);
        } else {
            add_to(bins, refs, n, map);
        }
        // Extents in units of the node's largest: areas of order one.
        const F4 extent = info.hi - info.lo;
        const float largest = std::max({extent[0], extent[1], extent[2]});
        const float inverse = 1.0f / largest;
        const F4 unit = F4{} + (largest > 0.0f && std::isfinite(inverse) ? inverse : 0.0f);
        // All three axes at once, a lane each: a sweep from the left gives the
        // cost of bins [0, i], one from the right that of the rest.
        float left_cost[kMaxBins][4];
        std::uint32_t left_count[kMaxBins][4];
        AxisBoxes boxes;
        I4 count{}, spheres{};
        for (int i = 0; i + 1 < map.bins; ++i) {
            boxes.add(bins[i]);
            count += load_counts(bins[i].count);
            spheres += load_counts(bins[i].spheres);
            const F4 cost = boxes.half_areas(unit) * weight(count, spheres);
            std::memcpy(left_cost[i], &cost, sizeof cost);
            std::memcpy(left_count[i], &count, sizeof count);
        }
        boxes = AxisBoxes{};
        count = spheres = I4{};
        F4 best_cost = F4{} + std::numeric_limits<float>::infinity();
        I4 best_bin{};
        for (int i = map.bins - 1; i > 0; --i) {
            boxes.add(bins[i]);
            count += load_counts(bins[i].count);
            spheres += load_counts(bins[i].spheres);
            F4 cost;
            std::memcpy(&cost, left_cost[i - 1], sizeof cost);
            cost += boxes.half_areas(unit) * weight(count, spheres);
            const I4 valid = (load_counts(left_count[i - 1]) > 0) & (count > 0);
            const I4 better = valid & (cost < best_cost);
            best_cost = better ? cost : best_cost;
            best_bin = better ? I4{} + i : best_bin;
        }
        for (int a = 0; a < 3; ++a)
            if (best_cost[a] < best.cost) {
                best.axis = a;
                best.bin = best_bin[a];
                best.cost = best_cost[a];
            }
        const F4 d = extent * unit;
        best.node_area = d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
        return best;
    }

    // Bins of many objects: two sets (Bins::add_pairs), whose second costs
    // its clearing and merging, a pass over the bins each.
    void add_to(Bins& bins, const PrimRef* refs, std::size_t n, const BinMap& map) const {
        if (n < static_cast<std::size_t>(kPairedBinsPerBin * map.bins)) {
            if (sphere_count_ > 0) bins.add<true>(refs, n, map, sphere_count_);
            else bins.add<false>(refs, n, map, sphere_count_);
            return;
        }
        Bins odd(map.bins);
        if (sphere_count_ > 0) bins.add_pairs<true>(odd, refs, n, map, sphere_count_);
        else bins.add_pairs<false>(odd, refs, n, map, sphere_count_);
        bins.merge(odd);
    }

    // In place: [begin, mid) go to the first child. Returns mid.
    static std::size_t partition(PrimRef* refs, std::size_t begin, std::size_t end, const BinMap& map,
                                 const Split& split, Info& left, Info& right) {
        std::size_t i = begin, j = end;
        while (i < j) {
            const F4 l = load_lo(refs[i]), h = load_hi(refs[i]);
            if (map.bin(centroid(l, h))[split.axis] < split.bin) {
                left.add(l, h);
                ++i;
            } else {
                right.add(l, h);
                --j;
                std::swap(refs[i], refs[j]);
            }
        }
        return i;
    }

    // From `from` into `to` over fixed blocks: each block's firsts and seconds
    // go where the counts of the blocks before it say, in block order.
    static std::size_t partition_parallel(const PrimRef* from, PrimRef* to, std::size_t begin, std::size_t end,
                                          const BinMap& map, const Split& split, Info& left, Info& right) {
        const std::size_t n = end - begin, blocks = detail::chunk_count(n, kBlock);
        std::vector<std::size_t> firsts(blocks + 1, 0);
        auto goes_first = [&](const PrimRef& r) { return map.bin(r)[split.axis] < split.bin; };
        detail::for_each_chunk(
            n,
            [&](std::size_t c, std::size_t b, std::size_t e) {
                std::size_t k = 0;
                for (std::size_t i = begin + b; i < begin + e; ++i) k += goes_first(from[i]) ? 1 : 0;
                firsts[c + 1] = k;
            },
            kBlock);
        std::vector<std::size_t> block_first(blocks), block_second(blocks);
        std::size_t at_first = begin, at_second = begin;
        for (std::size_t c = 0; c < blocks; ++c) at_second += firsts[c + 1];
        const std::size_t mid = at_second;
        for (std::size_t c = 0; c < blocks; ++c) {
            block_first[c] = at_first;
            block_second[c] = at_second;
            at_first += firsts[c + 1];
            at_second += std::min(n, (c + 1) * kBlock) - c * kBlock - firsts[c + 1];
        }
        std::vector<Info> lefts(blocks), rights(blocks);
        detail::for_each_chunk(
            n,
            [&](std::size_t c, std::size_t b, std::size_t e) {
                std::size_t f = block_first[c], s = block_second[c];
                for (std::size_t i = begin + b; i < begin + e; ++i) {
                    const PrimRef& r = from[i];
                    if (goes_first(r)) {
                        lefts[c].add(r);
                        to[f++] = r;
                    } else {
                        rights[c].add(r);
                        to[s++] = r;
                    }
                }
            },
            kBlock);
        for (std::size_t c = 0; c < blocks; ++c) {
            left.merge(lefts[c]);
            right.merge(rights[c]);
        }
        return mid;
    }

    static Info range_info(const PrimRef* refs, std::size_t begin, std::size_t end) {
        const std::size_t n = end - begin;
        std::vector<Info> parts(detail::chunk_count(n, kBlock));
        detail::for_each_chunk(
            n,
            [&](std::size_t c, std::size_t b, std::size_t e) {
                for (std::size_t i = begin + b; i < begin + e; ++i) parts[c].add(refs[i]);
            },
            kBlock);
        Info info;
        for (const Info& p : parts) info.merge(p);
        return info;
    }

    Bvh2Node leaf(std::size_t begin, std::size_t end, const Info& info, const PrimRef* refs) {
        std::uint32_t* ids = leaf_objects_ + begin;
        for (std::size_t i = begin; i < end; ++i) ids[i - begin] = refs[i].id;
        std::sort(ids, ids + (end - begin));
        report(end - begin);
        return make_node(info, static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(end - begin));
    }

    // Objects placed in leaves so far, reported to the progress callback at each percent.
    void report(std::size_t placed) {
        if (!config_.progress) return;
        const std::size_t before = placed_.fetch_add(placed, std::memory_order_relaxed);
        const std::size_t step = std::max<std::size_t>(total_ / 100, 1);
        if ((before + placed) / step == before / step) return;
        std::lock_guard lock(progress_mutex_);
        check_cancelled();  // no call after the one that cancelled
        const double done = static_cast<double>(placed_.load(std::memory_order_relaxed)) / static_cast<double>(total_);
        if (done <= reported_) return;
        reported_ = done;
        if (!config_.progress(std::min(done, 1.0))) {
            cancelled_.store(true, std::memory_order_relaxed);
            throw Error(ErrorCode::Cancelled, "BVH build cancelled");
        }
    }

    const BvhBuildConfig& config_;
    std::uint32_t sphere_count_;
    PrimRef* buffers_[2];
    std::uint32_t* leaf_objects_;
    std::size_t total_;
    int block_shift_;  // log2 of leaf_block
    std::atomic<std::size_t> placed_{0};
    std::atomic<bool> cancelled_{false};
    std::mutex progress_mutex_;
    double reported_ = 0.0;  // guarded by progress_mutex_
};

// The references of the objects with a box, in id order, and their Info.
// Throws InvalidArgument naming the first object whose box is out of range.
std::size_t make_refs(const BvhBuildInput& input, std::unique_ptr<PrimRef[]>& refs, Info& root) {
    const std::size_t count = input.bounds.size();
    const std::size_t chunks = detail::chunk_count(count);
    std::vector<std::size_t> first(chunks + 1, 0), bad(chunks, count);
    detail::for_each_chunk(count, [&](std::size_t c, std::size_t b, std::size_t e) {
        std::size_t k = 0;
        for (std::size_t id = b; id < e; ++id) {
            const detail::BoxUse use = detail::box_use(input.bounds[id]);
            if (use == detail::BoxUse::Refused) {
                bad[c] = id;
                return;
            }
            k += use == detail::BoxUse::Held ? 1 : 0;
        }
        first[c + 1] = k;
    });
    for (std::size_t c = 0; c < chunks; ++c)
        if (bad[c] < count)
            throw Error(ErrorCode::InvalidArgument, "BVH input: object " + std::to_string(bad[c]) +
                                                        " has bounds that are NaN, infinite or beyond the float range");
    for (std::size_t c = 0; c < chunks; ++c) first[c + 1] += first[c];
    const std::size_t n = first[chunks];
    refs.reset(new PrimRef[std::max<std::size_t>(n, 1)]);
    std::vector<Info> infos(chunks);
    detail::for_each_chunk(count, [&](std::size_t c, std::size_t b, std::size_t e) {
        std::size_t at = first[c];
        for (std::size_t id = b; id < e; ++id) {
            const Aabb& box = input.bounds[id];
            if (box.empty()) continue;
            const detail::FloatBox f = detail::round_out(box);
            PrimRef& r = refs[at++];
            for (int a = 0; a < 3; ++a) {
                r.lo[a] = f.lo[a];
                r.hi[a] = f.hi[a];
            }
            r.id = static_cast<std::uint32_t>(id);
            r.zero = 0.0f;
            infos[c].add(r);
        }
    });
    for (const Info& i : infos) root.merge(i);
    return n;
}

}  // namespace

Bvh2 build_bvh2(const BvhBuildInput& input, const BvhBuildConfig& config) {
    config.validate();
    constexpr std::size_t kMaxObjects = std::size_t{1} << 31;  // 2n - 1 node indices must fit 32 bits
    if (input.bounds.size() >= kMaxObjects)
        throw Error(ErrorCode::Unsupported, "BVH builder: " + std::to_string(input.bounds.size()) +
                                                " objects, at most 2^31 - 1 are supported");
    if (input.sphere_count > input.bounds.size())
        throw Error(ErrorCode::InvalidArgument, "BVH input: sphere_count " + std::to_string(input.sphere_count) +
                                                    " exceeds the " + std::to_string(input.bounds.size()) + " objects");
    Bvh2 bvh;
    bvh.object_count = static_cast<std::uint32_t>(input.bounds.size());
    tbb::task_arena arena(config.threads > 0 ? config.threads : tbb::task_arena::automatic);
    auto run = [&] {
        std::unique_ptr<PrimRef[]> refs;
        Info root_info;
        const std::size_t n = make_refs(input, refs, root_info);
        if (n == 0) return;
        // The partitions of large nodes scatter into the other buffer.
        std::unique_ptr<PrimRef[]> other(n >= kParallelObjects ? new PrimRef[n] : nullptr);
        bvh.leaf_objects.resize(n);
        BinnedBuild build(config, input.sphere_count, refs.get(), other.get(), bvh.leaf_objects.data(), n);
        Fragment root;
        root.nodes.reserve(2 * n);
        root.nodes.emplace_back();
        const Bvh2Node top = build.node(0, n, root_info, 0, 0, root);
        root.nodes[0] = top;
        refs.reset();
        other.reset();
        flatten(root, bvh.nodes);
    };
    {
        detail::TsanForkJoin tsan;
        arena.execute(tsan.task(run));
    }
    return bvh;
}

}  // namespace kdrt
