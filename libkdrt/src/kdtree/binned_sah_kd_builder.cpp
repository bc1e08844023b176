// Binned SAH kd-tree builder, after I. Wald, "On fast Construction of
// SAH-based Bounding Volume Hierarchies" (IRT 2007) and M. Shevtsov, A.
// Soupikov, A. Kapustin, "Highly Parallel Fast KD-tree Construction for
// Interactive Ray Tracing of Dynamic Scenes" (Eurographics 2007):
//  - a node with more than exact_threshold objects evaluates the SAH only at
//    bins - 1 evenly spaced planes per axis, from per-bin counts of where the
//    objects start and end (one pass over the objects); below the threshold
//    the exact O(N log N) sweep of Wald and Havran 2006 takes over
//    (sah_kd_builder.cpp);
//  - a node of n objects uses n bins (at least 8, at most sah_bins): more bins
//    than objects mostly sweep empty ones. With that, binning small nodes
//    costs less than the exact sweep's event lists for trees of about the
//    same SAH cost;
//  - objects straddling the plane are clipped to both child cells with
//    input.clip ("perfect splits"), so long triangles leave the cells they
//    do not reach;
//  - parallel over subtrees (a large node's children are two tasks: the
//    below child writes on into the node's depth-first arrays, the above
//    child into a fragment of its own, copied into the tree once at the end
//    by flatten) and, at the
//    top levels, over objects: binning and partitioning run over fixed-size
//    blocks, summed and concatenated in block order, so the tree is the same,
//    byte for byte, for any number of threads.
// Planes are floats and objects are float boxes rounded outward, so the stored
// split classifies every object exactly as the builder did. The cost model,
// the empty-space bonus, the per-object intersection costs and the
// duplication allowance are those of the exact builder (KdBuildContext).
#include "kdtree/binned_sah_kd_builder.h"

#include "common/parallel_chunks.h"
#include "kdtree/kd_build_common.h"
#include "kdtree/sah_kd_builder.h"
#include "common/tsan_fork_join.h"

#include <kdrt/error.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace kdrt {

namespace {

using detail::KdRef;

// A node's bins: one per object, within [kMinBins, sah_bins].
constexpr int kMinBins = 8;
// Only the axes at least this fraction of the cell's longest side are binned
// and swept: a cut across a short side rarely wins, and skipping it saves
// both build time and nodes.
constexpr double kAxisFraction = 0.5;
// Nodes at least this large build their two children as parallel tasks.
constexpr std::size_t kParallelSubtree = 1024;
// Nodes at least this large are binned and partitioned in parallel, over
// blocks of kBlock objects (a fixed size: the results never depend on the
// thread count).
constexpr std::size_t kParallelObjects = std::size_t{1} << 16;
constexpr std::size_t kBlock = std::size_t{1} << 14;

struct BinSplit {
    int axis = -1;
    float pos = 0.0f;
    double cost = std::numeric_limits<double>::infinity();
};

// Per axis and bin, the summed weights of the objects starting and ending
// there. Up to kLocal bins live in the object itself: most nodes are small, and
// their bins should cost no allocation.
class Bins {
public:
    explicit Bins(int bins) : bins_(bins) {
        if (bins > kLocal) heap_.resize(6 * static_cast<std::size_t>(bins));
        std::fill_n(data(), 6 * static_cast<std::size_t>(bins), std::uint64_t{0});
    }
    int count() const { return bins_; }
    std::uint64_t* start(int axis) { return data() + static_cast<std::ptrdiff_t>(axis) * bins_; }
    std::uint64_t* end(int axis) { return data() + static_cast<std::ptrdiff_t>(3 + axis) * bins_; }
    const std::uint64_t* start(int axis) const { return data() + static_cast<std::ptrdiff_t>(axis) * bins_; }
    const std::uint64_t* end(int axis) const { return data() + static_cast<std::ptrdiff_t>(3 + axis) * bins_; }
    void add(const Bins& o) {
        const std::uint64_t* from = o.data();
        std::uint64_t* to = data();
        for (std::size_t i = 0; i < 6 * static_cast<std::size_t>(bins_); ++i) to[i] += from[i];
        total += o.total;
    }
    std::uint64_t total = 0;

private:
    static constexpr int kLocal = 64;
    std::uint64_t* data() { return heap_.empty() ? local_.data() : heap_.data(); }
    const std::uint64_t* data() const { return heap_.empty() ? local_.data() : heap_.data(); }
    int bins_;
    std::array<std::uint64_t, 6 * kLocal> local_;  // start by axis, then end by axis
    std::vector<std::uint64_t> heap_;
};

// The axes a node's split is looked for on (kAxisFraction), in axis order.
struct SplitAxes {
    int axis[3];
    int count = 0;
    explicit SplitAxes(const Aabb& cell) {
        const glm::dvec3 d = cell.extent();
        const double longest = std::max({d.x, d.y, d.z});
        for (int k = 0; k < 3; ++k)
            if (d[k] > 0.0 && d[k] >= kAxisFraction * longest) axis[count++] = k;
    }
    bool uses(int k) const { return std::find(axis, axis + count, k) != axis + count; }
};

enum Place : std::uint8_t { kBelow, kAbove, kStraddles };

inline Place place(const KdRef& r, int axis, float p) {
    if (r.hi[axis] <= p) return kBelow;  // touching the plane from below, or lying in it
    if (r.lo[axis] >= p) return kAbove;
    return kStraddles;
}

// Room for the tree over `refs` objects as big meshes' trees need it
// (reserved, not touched: no pages until used), so that its arrays are not
// copied as they grow: for the root, and for a fragment that will hold its
// whole subtree (one built serially; see Fragment).
void reserve_for(KdTree& tree, std::size_t refs) {
    tree.nodes.reserve(tree.nodes.size() + 2 * refs);
    tree.leaf_objects.reserve(tree.leaf_objects.size() + 3 * refs);
}

// A subtree built by a parallel task, laid out as the final tree will hold
// it (depth first, the below child next): its own nodes first (the path of
// below children down to the first node built serially, and that node's
// subtree), then the above subtrees of that path's parallel nodes, deepest
// first, each a fragment of its own. Indices count from the fragment's start
// and include the fragments after its own nodes (logical_*), so the finished
// tree is one copy of each fragment (flatten), not one per parallel level
// above it (6 to 8 copies of a node on the 1M torus and the 2M heightfield).
struct Fragment {
    KdTree tree;  // the own nodes and their leaf lists
    std::vector<std::unique_ptr<Fragment>> after;
    std::size_t after_nodes = 0, after_refs = 0;

    std::size_t logical_nodes() const { return tree.nodes.size() + after_nodes; }
    std::size_t logical_refs() const { return tree.leaf_objects.size() + after_refs; }
    void append(std::unique_ptr<Fragment> f) {
        if (logical_nodes() + f->logical_nodes() > KDRT_MAX_NODE_INDEX)
            throw Error(ErrorCode::Unsupported,
                        "kd-tree too large: more than " + std::to_string(KDRT_MAX_NODE_INDEX) + " nodes");
        if (logical_refs() + f->logical_refs() > std::numeric_limits<std::uint32_t>::max())
            throw Error(ErrorCode::Unsupported, "kd-tree too large: more than 2^32-1 leaf references");
        after_nodes += f->logical_nodes();
        after_refs += f->logical_refs();
        after.push_back(std::move(f));
    }
};

// Copies the fragments after root's own nodes into root.tree, each once, in
// their order, in parallel (serially, it would be a pass over nearly the whole
// tree on one thread).
void flatten(Fragment& root) {
    struct Placed {
        Fragment* fragment;
        std::size_t node_offset, ref_offset;
    };
    std::vector<Placed> placed;
    std::size_t nodes = root.tree.nodes.size(), refs = root.tree.leaf_objects.size();
    auto place = [&](auto& self, Fragment& f) -> void {
        placed.push_back({&f, nodes, refs});
        nodes += f.tree.nodes.size();
        refs += f.tree.leaf_objects.size();
        for (auto& next : f.after) self(self, *next);
    };
    for (auto& f : root.after) place(place, *f);
    root.tree.nodes.resize(nodes);
    root.tree.leaf_objects.resize(refs);
    auto copy = [&](std::size_t i) {
        const Placed& p = placed[i];
        const KdTree& from = p.fragment->tree;
        const auto node_offset = static_cast<std::uint32_t>(p.node_offset);
        const auto ref_offset = static_cast<std::uint32_t>(p.ref_offset);
        KdNode* to = root.tree.nodes.data() + p.node_offset;
        for (const KdNode& n : from.nodes) *to++ = detail::kd_shifted(n, node_offset, ref_offset);
        std::copy(from.leaf_objects.begin(), from.leaf_objects.end(),
                  root.tree.leaf_objects.begin() + static_cast<std::ptrdiff_t>(p.ref_offset));
        p.fragment->tree = {};
    };
    {
        detail::TsanForkJoin tsan;
        tbb::parallel_for(std::size_t{0}, placed.size(), tsan.task(copy));
    }
    root.after.clear();
    root.after_nodes = root.after_refs = 0;
}

class BinnedBuild {
public:
    BinnedBuild(detail::KdBuildContext& ctx, const KdBuildConfig& config, int max_depth)
        : ctx_(ctx),
          bins_(config.sah_bins),
          exact_threshold_(config.exact_threshold),
          max_depth_(max_depth),
          empty_bonus_(config.empty_bonus) {}

    // Builds the subtree over refs (the node's objects clipped to cell) and
    // appends it to out, depth-first. The node's refs bytes are charged.
    // `binned`, if given, is refs binned with sah_bins bins (by the parent's partition).
    // Own nodes are written only while `out` has no fragments after them (see Fragment).
    void node(std::vector<KdRef> refs, const Aabb& cell, int depth, double allowance, Fragment& out,
              const Bins* binned = nullptr) {
        ctx_.check_cancelled();
        const std::size_t n = refs.size();
        if (n <= exact_threshold_ || depth >= max_depth_) {
            detail::build_exact_sah_subtree(ctx_, max_depth_, empty_bonus_, refs, cell, depth, allowance, out.tree);
            ctx_.release(n * sizeof(KdRef));
            return;
        }
        std::uint64_t total = 0;
        const BinSplit split = find_split(refs, cell, total, binned);
        if (split.axis < 0 || split.cost >= static_cast<double>(total)) {
            leaf(std::move(refs), allowance, out);
            return;
        }
        const int axis = split.axis;
        const float p = split.pos;
        Aabb below_cell = cell, above_cell = cell;
        below_cell.hi[axis] = p;
        above_cell.lo[axis] = p;

        std::vector<KdRef> above;
        // A big node's children are binned by its partition, while their
        // refs are still in cache: a pass over memory less per level.
        std::vector<Bins> child_bins;  // below, above: only for a big node (a Bins is kilobytes)
        if (n >= kParallelObjects) child_bins.assign(2, Bins(bins_));
        const Counts c = n >= kParallelObjects
                             ? partition_parallel(refs, above, cell, axis, p, below_cell, above_cell, child_bins[0],
                                                  child_bins[1])
                             : partition(refs, above, cell, axis, p, below_cell, above_cell);
        // Bounded duplication (KdBuildContext), counted as the objects lay
        // before the straddlers were clipped. Past it (rare: a tree that
        // explodes), the node becomes a leaf of what the two lists hold.
        if (static_cast<double>(c.below + c.above + 2 * c.straddles) > allowance) {
            refs.insert(refs.end(), above.begin(), above.end());  // the bytes charged for above move to refs
            above = {};
            leaf(std::move(refs), allowance, out);
            return;
        }
        const double share = allowance / static_cast<double>(std::max<std::size_t>(refs.size() + above.size(), 1));
        const double below_allowance = share * static_cast<double>(refs.size());
        const double above_allowance = share * static_cast<double>(above.size());

        const std::size_t index = out.tree.nodes.size();
        out.tree.nodes.emplace_back();
        if (n >= kParallelSubtree) {
            // The below child goes straight into `out` (no other task writes
            // there meanwhile); the above child is built apart, a fragment after it.
            auto above_fragment = std::make_unique<Fragment>();
            // A bigger one holds only a path of nodes and a subtree under kParallelSubtree,
            // and lives until flatten: room for all its objects would add up to a third of the peak.
            if (above.size() < kParallelSubtree) reserve_for(above_fragment->tree, above.size());
            const Bins* binned_below = child_bins.empty() ? nullptr : &child_bins[0];
            const Bins* binned_above = child_bins.empty() ? nullptr : &child_bins[1];
            auto build_below = [&] { node(std::move(refs), below_cell, depth + 1, below_allowance, out, binned_below); };
            auto build_above = [&] {
                node(std::move(above), above_cell, depth + 1, above_allowance, *above_fragment, binned_above);
            };
            {
                detail::TsanForkJoin tsan;
                tbb::parallel_invoke(tsan.task(build_below), tsan.task(build_above));
            }
            out.tree.nodes[index] = kd_make_inner(axis, p, static_cast<std::uint32_t>(out.logical_nodes()));
            out.append(std::move(above_fragment));
        } else {
            node(std::move(refs), below_cell, depth + 1, below_allowance, out);
            out.tree.nodes[index] = kd_make_inner(axis, p, static_cast<std::uint32_t>(out.tree.nodes.size()));
            node(std::move(above), above_cell, depth + 1, above_allowance, out);
        }
    }

private:
    struct Counts {
        std::size_t below = 0, above = 0, straddles = 0;
    };

    void leaf(std::vector<KdRef> refs, double allowance, Fragment& out) {
        // Most leaves hold a few objects: their ids sort on the stack, not in
        // an allocation per leaf.
        constexpr std::size_t kOnStack = 32;
        std::uint32_t on_stack[kOnStack];
        std::vector<std::uint32_t> on_heap;
        std::uint32_t* ids = on_stack;
        if (refs.size() > kOnStack) {
            on_heap.resize(refs.size());
            ids = on_heap.data();
        }
        for (std::size_t i = 0; i < refs.size(); ++i) ids[i] = refs[i].id;
        const std::size_t listed = refs.size();
        ctx_.release(listed * sizeof(KdRef));
        refs = {};
        std::sort(ids, ids + listed);
        const auto count = static_cast<std::size_t>(std::unique(ids, ids + listed) - ids);  // a split undone lists straddlers twice
        ctx_.charge(detail::KdBuildContext::leaf_bytes(count));
        detail::kd_emit_leaf(out.tree, std::span<const std::uint32_t>(ids, count));
        ctx_.leaf_done(allowance);
    }

    // Bins one range of refs (Wald 2007): per axis, the bin holding each
    // object's lower bound and the one holding its upper bound. A bound
    // exactly on a bin boundary counts on the side the partition will put it.
    void bin(const KdRef* first, const KdRef* last, const Aabb& cell, const SplitAxes& axes, int bins, Bins& b) const {
        const auto k_bins = static_cast<float>(bins);
        float lo[3], scale[3];
        for (int k = 0; k < 3; ++k) {
            lo[k] = static_cast<float>(cell.lo[k]);
            const double extent = cell.hi[k] - cell.lo[k];
            scale[k] = extent > 0.0 ? static_cast<float>(bins / extent) : 0.0f;
        }
        const int top = bins - 1;
#if defined(__SSE2__)
        // All three axes at once in one vector (lane 3 is unused). The same
        // bins as the scalar code below: small integers are exact in float.
        const __m128 v_lo = _mm_setr_ps(lo[0], lo[1], lo[2], 0.0f);
        const __m128 v_scale = _mm_setr_ps(scale[0], scale[1], scale[2], 0.0f);
        const __m128 v_bins = _mm_set1_ps(k_bins), v_top = _mm_set1_ps(static_cast<float>(top));
        const __m128 v_zero = _mm_setzero_ps(), v_one = _mm_set1_ps(1.0f);
        // Clears lane 3 of the hi load, which holds the id's bits: as a float,
        // an id below 2^23 is a denormal, and arithmetic on denormals is slow.
        const __m128 first3 = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
        const bool use[3] = {axes.uses(0), axes.uses(1), axes.uses(2)};
        std::uint64_t* start[3] = {b.start(0), b.start(1), b.start(2)};
        std::uint64_t* end[3] = {b.end(0), b.end(1), b.end(2)};
        std::uint64_t total = 0;
        for (const KdRef* r = first; r != last; ++r) {
            const std::uint64_t w = ctx_.weight(r->id);
            total += w;
            // lo[0..2] and hi[0..2], each with the next member as a fourth float (unused).
            const __m128 r_lo = _mm_loadu_ps(r->lo), r_hi = _mm_and_ps(_mm_loadu_ps(r->hi), first3);
            // minps returns its second operand when one is NaN (0 * inf, in a cell so
            // small that its scale overflows), and std::min(x, bins) returns x: x goes second.
            const __m128 s = _mm_min_ps(_mm_max_ps(_mm_min_ps(v_bins, _mm_mul_ps(_mm_sub_ps(r_lo, v_lo), v_scale)), v_zero), v_top);
            const __m128 e = _mm_min_ps(v_bins, _mm_mul_ps(_mm_sub_ps(r_hi, v_lo), v_scale));
            const __m128 s_bin = _mm_cvtepi32_ps(_mm_cvttps_epi32(s));
            const __m128 e_trunc = _mm_cvtepi32_ps(_mm_cvttps_epi32(e));
            const __m128 e_bin = _mm_sub_ps(e_trunc, _mm_and_ps(_mm_cmpeq_ps(e_trunc, e), v_one));  // ceil(e) - 1
            const __m128i bs = _mm_cvttps_epi32(s_bin);
            const __m128i be = _mm_cvttps_epi32(_mm_min_ps(_mm_max_ps(e_bin, s_bin), v_top));
            // Lanes to registers, not through memory: a store and reloads would wait on each other.
            if (use[0]) {
                start[0][_mm_cvtsi128_si32(bs)] += w;
                end[0][_mm_cvtsi128_si32(be)] += w;
            }
            if (use[1]) {
                start[1][_mm_cvtsi128_si32(_mm_shuffle_epi32(bs, 0x55))] += w;
                end[1][_mm_cvtsi128_si32(_mm_shuffle_epi32(be, 0x55))] += w;
            }
            if (use[2]) {
                start[2][_mm_cvtsi128_si32(_mm_shuffle_epi32(bs, 0xaa))] += w;
                end[2][_mm_cvtsi128_si32(_mm_shuffle_epi32(be, 0xaa))] += w;
            }
        }
        b.total += total;
#else
        std::uint64_t* start[3] = {b.start(0), b.start(1), b.start(2)};
        std::uint64_t* end[3] = {b.end(0), b.end(1), b.end(2)};
        for (const KdRef* r = first; r != last; ++r) {
            const std::uint64_t w = ctx_.weight(r->id);
            b.total += w;
            for (int j = 0; j < axes.count; ++j) {
                const int k = axes.axis[j];
                const float s = std::min((r->lo[k] - lo[k]) * scale[k], k_bins);
                const float e = std::min((r->hi[k] - lo[k]) * scale[k], k_bins);
                const int bs = std::clamp(static_cast<int>(s), 0, top);
                // ceil(e) - 1 for e >= 0, without a libm call (e is an integer exactly when it is a boundary)
                const int te = static_cast<int>(e);
                const int be = std::clamp(te - (static_cast<float>(te) == e), bs, top);
                start[k][bs] += w;
                end[k][be] += w;
            }
        }
#endif
    }

    BinSplit find_split(const std::vector<KdRef>& refs, const Aabb& cell, std::uint64_t& total,
                        const Bins* binned) const {
        const auto fewest = static_cast<std::size_t>(std::min(kMinBins, bins_));
        const int bins = static_cast<int>(std::clamp(refs.size(), fewest, static_cast<std::size_t>(bins_)));
        const SplitAxes axes(cell);
        if (binned && binned->count() == bins) return sweep(*binned, cell, axes, bins, total);
        Bins b(bins);
        fill_bins(refs, cell, axes, bins, b);
        return sweep(b, cell, axes, bins, total);
    }

    // The node's bins: in parallel over fixed blocks for a big node.
    void fill_bins(const std::vector<KdRef>& refs, const Aabb& cell, const SplitAxes& axes, int bins, Bins& b) const {
        if (refs.size() >= kParallelObjects) {
            // One Bins per fixed block, summed in block order afterwards.
            const std::size_t blocks = (refs.size() + kBlock - 1) / kBlock;
            std::vector<Bins> parts(blocks, Bins(bins));
            auto bin_block = [&](std::size_t blk) {
                const std::size_t first = blk * kBlock, last = std::min(refs.size(), first + kBlock);
                bin(refs.data() + first, refs.data() + last, cell, axes, bins, parts[blk]);
            };
            {
                detail::TsanForkJoin tsan;
                tbb::parallel_for(std::size_t{0}, blocks, tsan.task(bin_block));
            }
            for (const Bins& part : parts) b.add(part);
        } else {
            bin(refs.data(), refs.data() + refs.size(), cell, axes, bins, b);
        }
    }

    // The best plane over the bins (SAH with the empty-space bonus).
    BinSplit sweep(const Bins& b, const Aabb& cell, const SplitAxes& axes, int bins, std::uint64_t& total) const {
        total = b.total;

        BinSplit best;
        const double area = cell.surface_area();
        if (!(area > 0.0)) return best;
        const double inv_area = 1.0 / area;
        const double traversal = ctx_.traversal_cost(), bonus_factor = 1.0 - empty_bonus_;
        const glm::dvec3 d = cell.extent();
        for (int j = 0; j < axes.count; ++j) {
            const int k = axes.axis[j];
            const double lo = cell.lo[k], hi = cell.hi[k];
            const double cross = d[(k + 1) % 3] * d[(k + 2) % 3];
            const double perimeter = d[(k + 1) % 3] + d[(k + 2) % 3];
            // Weights as signed integers: converting those to double is one
            // instruction, an unsigned one a branch (the sums stay far below 2^63).
            const auto* start = reinterpret_cast<const std::int64_t*>(b.start(k));
            const auto* end = reinterpret_cast<const std::int64_t*>(b.end(k));
            // In chunks of arrays, so that the costs are computed a vector at a
            // time and the search for the best is branch-free (the best plane
            // moves unpredictably along a sweep). The first of equal costs
            // wins, per axis and across axes, as in one sequential search.
            auto sweep = [&](auto checked) {
                constexpr int kChunk = 64;
                alignas(16) double w_b[kChunk], w_a[kChunk], cost[kChunk];
                alignas(16) float pos[kChunk];  // kChunk even: a last odd plane has room for its pair
                std::int64_t w_below = 0, w_above = static_cast<std::int64_t>(b.total);
                float previous = -std::numeric_limits<float>::infinity();
                double axis_cost = best.cost;
                float axis_pos = 0.0f;
                for (int first = 1; first < bins; first += kChunk) {
                    const int m = std::min(kChunk, bins - first);
                    for (int x = 0; x < m; ++x) {
                        w_below += start[first + x - 1];
                        w_above -= end[first + x - 1];
                        w_b[x] = static_cast<double>(w_below);
                        w_a[x] = static_cast<double>(w_above);
                    }
#if defined(__SSE2__)
                    // Two planes a vector, in the scalar code's order of operations (same costs, bit for bit).
                    if (m % 2) w_b[m] = w_a[m] = 0.0;
                    const __m128d v_lo = _mm_set1_pd(lo), v_hi = _mm_set1_pd(hi), v_ext = _mm_set1_pd(hi - lo);
                    const __m128d v_bins = _mm_set1_pd(bins), v_cross = _mm_set1_pd(cross);
                    const __m128d v_perimeter = _mm_set1_pd(perimeter), v_inv_area = _mm_set1_pd(inv_area);
                    const __m128d v_two = _mm_set1_pd(2.0), v_traversal = _mm_set1_pd(traversal);
                    const __m128d v_bonus = _mm_set1_pd(bonus_factor), v_zero = _mm_setzero_pd();
                    for (int x = 0; x < m; x += 2) {
                        const __m128d i = _mm_cvtepi32_pd(_mm_setr_epi32(first + x, first + x + 1, 0, 0));
                        const __m128 p_f = _mm_cvtpd_ps(_mm_add_pd(v_lo, _mm_div_pd(_mm_mul_pd(v_ext, i), v_bins)));
                        _mm_storel_pi(reinterpret_cast<__m64*>(pos + x), p_f);
                        const __m128d p = _mm_cvtps_pd(p_f);
                        const __m128d p_below = _mm_mul_pd(
                            _mm_mul_pd(v_two, _mm_add_pd(v_cross, _mm_mul_pd(_mm_sub_pd(p, v_lo), v_perimeter))), v_inv_area);
                        const __m128d p_above = _mm_mul_pd(
                            _mm_mul_pd(v_two, _mm_add_pd(v_cross, _mm_mul_pd(_mm_sub_pd(v_hi, p), v_perimeter))), v_inv_area);
                        const __m128d wb = _mm_load_pd(w_b + x), wa = _mm_load_pd(w_a + x);
                        const __m128d c = _mm_add_pd(_mm_add_pd(v_traversal, _mm_mul_pd(p_below, wb)), _mm_mul_pd(p_above, wa));
                        const __m128d empty = _mm_or_pd(_mm_cmpeq_pd(wb, v_zero), _mm_cmpeq_pd(wa, v_zero));
                        _mm_store_pd(cost + x, _mm_or_pd(_mm_and_pd(empty, _mm_mul_pd(c, v_bonus)), _mm_andnot_pd(empty, c)));
                    }
#else
                    for (int x = 0; x < m; ++x) {
                        const float p = static_cast<float>(lo + (hi - lo) * (first + x) / bins);
                        pos[x] = p;
                        const double p_below = 2.0 * (cross + (p - lo) * perimeter) * inv_area;
                        const double p_above = 2.0 * (cross + (hi - p) * perimeter) * inv_area;
                        const double c = traversal + p_below * w_b[x] + p_above * w_a[x];
                        cost[x] = (w_b[x] == 0.0 || w_a[x] == 0.0) ? c * bonus_factor : c;
                    }
#endif
                    if constexpr (decltype(checked)::value) {
                        for (int x = 0; x < m; ++x) {
                            const float p = pos[x];
                            if (!(lo < p && p < hi) || p == previous) cost[x] = std::numeric_limits<double>::infinity();
                            else previous = p;
                        }
                    }
                    for (int x = 0; x < m; ++x) {
                        const bool better = cost[x] < axis_cost;
                        axis_cost = better ? cost[x] : axis_cost;
                        axis_pos = better ? pos[x] : axis_pos;
                    }
                }
                if (axis_cost < best.cost) best = {k, axis_pos, axis_cost};
            };
            // Bin boundaries more than two float steps apart round to distinct
            // planes strictly inside the cell: no plane to skip, no check.
            const double step_bound = std::max(std::abs(lo), std::abs(hi)) * 0x1p-23 + 0x1p-126;
            if ((hi - lo) / bins > 2.0 * step_bound) sweep(std::false_type{});
            else sweep(std::true_type{});
        }
        return best;
    }

    // Perfect split of one straddling object: its parts in the two child cells.
    void split_straddler(const KdRef& r, const Aabb& cell, int axis, float p, const Aabb& below_cell,
                         const Aabb& above_cell, KdRef& below, bool& has_below, KdRef& above, bool& has_above) const {
        Aabb b, a;
        detail::kd_split_object(ctx_.input, r.id, cell, axis, p, b, a);
        if (b.empty() && a.empty()) {  // a clip function disagreeing with the bounds: stay conservative
            b = detail::kd_ref_box(r).intersect(below_cell);
            a = detail::kd_ref_box(r).intersect(above_cell);
        }
        has_below = !b.empty();
        has_above = !a.empty();
        if (has_below) below = detail::kd_make_ref(r.id, b);
        if (has_above) above = detail::kd_make_ref(r.id, a);
    }

    // refs becomes the below child's list, in place; above is filled.
    // Returns where the objects lay against the plane, before clipping.
    Counts partition(std::vector<KdRef>& refs, std::vector<KdRef>& above, const Aabb& cell, int axis, float p,
                     const Aabb& below_cell, const Aabb& above_cell) {
        const std::size_t n = refs.size();
        above.reserve(n);
        Counts c;
        std::size_t kept = 0;
        for (std::size_t i = 0; i < n; ++i) {
            // A 28-byte KdRef is copied as two overlapping 16-byte halves: a
            // copy into a local, and a copy onto itself (kept == i), each read
            // back a half that overlapped the other half's store, and stalled
            // on store forwarding for every object. So a reference, and no
            // self-copy. refs[kept] (kept <= i) is written only after r is read.
            const KdRef& r = refs[i];
            switch (place(r, axis, p)) {
                case kBelow:
                    if (kept != i) refs[kept] = r;
                    ++kept;
                    ++c.below;
                    break;
                case kAbove: above.push_back(r); ++c.above; break;
                case kStraddles: {
                    ++c.straddles;
                    KdRef b, a;
                    bool has_b = false, has_a = false;
                    split_straddler(r, cell, axis, p, below_cell, above_cell, b, has_b, a, has_a);
                    if (has_b) refs[kept++] = b;
                    if (has_a) above.push_back(a);
                    break;
                }
            }
        }
        refs.resize(kept);
        ctx_.release((n - kept) * sizeof(KdRef));
        ctx_.charge(above.size() * sizeof(KdRef));
        return c;
    }

    // The same over fixed blocks in parallel, concatenated in block order.
    // Also bins the two children with sah_bins bins, each block's part as it
    // is made (children of a big node are big: fewer objects than bins is rare,
    // and those are binned again).
    Counts partition_parallel(std::vector<KdRef>& refs, std::vector<KdRef>& above, const Aabb& cell, int axis,
                              float p, const Aabb& below_cell, const Aabb& above_cell, Bins& below_bins,
                              Bins& above_bins) {
        const std::size_t n = refs.size(), blocks = (n + kBlock - 1) / kBlock;
        std::vector<std::vector<KdRef>> below_parts(blocks), above_parts(blocks);
        std::vector<Counts> counts(blocks);
        const SplitAxes below_axes(below_cell), above_axes(above_cell);
        std::vector<Bins> below_block_bins(blocks, Bins(bins_)), above_block_bins(blocks, Bins(bins_));
        auto split_block = [&](std::size_t blk) {
            const std::size_t first = blk * kBlock, last = std::min(n, first + kBlock);
            std::vector<KdRef>& bp = below_parts[blk];
            std::vector<KdRef>& ap = above_parts[blk];
            Counts& c = counts[blk];
            for (std::size_t i = first; i < last; ++i) {
                const KdRef& r = refs[i];
                switch (place(r, axis, p)) {
                    case kBelow: bp.push_back(r); ++c.below; break;
                    case kAbove: ap.push_back(r); ++c.above; break;
                    case kStraddles: {
                        ++c.straddles;
                        KdRef b, a;
                        bool has_b = false, has_a = false;
                        split_straddler(r, cell, axis, p, below_cell, above_cell, b, has_b, a, has_a);
                        if (has_b) bp.push_back(b);
                        if (has_a) ap.push_back(a);
                        break;
                    }
                }
            }
            bin(bp.data(), bp.data() + bp.size(), below_cell, below_axes, bins_, below_block_bins[blk]);
            bin(ap.data(), ap.data() + ap.size(), above_cell, above_axes, bins_, above_block_bins[blk]);
        };
        {
            detail::TsanForkJoin tsan;
            tbb::parallel_for(std::size_t{0}, blocks, tsan.task(split_block));
        }
        // The parts in block order into `into`, which may be `refs` itself:
        // the below list never outgrows it, and reusing it spares touching
        // fresh pages at every level of a big mesh.
        auto concatenate = [&](std::vector<std::vector<KdRef>>& parts, std::vector<KdRef>& into) {
            std::vector<std::size_t> offset(blocks + 1, 0);
            for (std::size_t blk = 0; blk < blocks; ++blk) offset[blk + 1] = offset[blk] + parts[blk].size();
            into.resize(offset[blocks]);
            auto copy_block = [&](std::size_t blk) {
                std::copy(parts[blk].begin(), parts[blk].end(),
                          into.begin() + static_cast<std::ptrdiff_t>(offset[blk]));
                parts[blk] = {};
            };
            {
                detail::TsanForkJoin tsan;
                tbb::parallel_for(std::size_t{0}, blocks, tsan.task(copy_block));
            }
        };
        concatenate(below_parts, refs);
        ctx_.release((n - refs.size()) * sizeof(KdRef));
        ctx_.charge(parts_size(above_parts) * sizeof(KdRef));
        concatenate(above_parts, above);
        for (std::size_t blk = 0; blk < blocks; ++blk) {
            below_bins.add(below_block_bins[blk]);
            above_bins.add(above_block_bins[blk]);
        }
        Counts total;
        for (const Counts& c : counts) {
            total.below += c.below;
            total.above += c.above;
            total.straddles += c.straddles;
        }
        return total;
    }

    static std::size_t parts_size(const std::vector<std::vector<KdRef>>& parts) {
        std::size_t total = 0;
        for (const auto& p : parts) total += p.size();
        return total;
    }

    detail::KdBuildContext& ctx_;
    int bins_;
    std::size_t exact_threshold_;
    int max_depth_;
    double empty_bonus_;
};

}  // namespace

KdTree detail::build_binned_sah_kd_tree(const KdBuildInput& input, const KdBuildConfig& config) {
    if (input.bounds.size() > (std::size_t{1} << 30))
        throw Error(ErrorCode::Unsupported, "SAH kd-tree builder: " + std::to_string(input.bounds.size()) +
                                                " objects, at most 2^30 are supported");
    KdTree tree;
    tbb::task_arena arena(config.threads > 0 ? config.threads : tbb::task_arena::automatic);
    auto run = [&] {
        tree.bounds = detail::kd_root_cell(input);
        tree.object_count = static_cast<std::uint32_t>(input.bounds.size());
        // Objects with a box get a reference, in id order: counted per chunk,
        // then each chunk's references made in parallel at their place.
        const std::size_t count = input.bounds.size();
        std::vector<std::size_t> first_ref(detail::chunk_count(count) + 1, 0);
        detail::for_each_chunk(count, [&](std::size_t c, std::size_t begin, std::size_t end) {
            std::size_t boxes = 0;
            for (std::size_t id = begin; id < end; ++id) boxes += input.bounds[id].empty() ? 0 : 1;
            first_ref[c + 1] = boxes;
        });
        for (std::size_t c = 1; c < first_ref.size(); ++c) first_ref[c] += first_ref[c - 1];
        const std::size_t n = first_ref.back();
        tree.max_depth = config.max_depth > 0 ? config.max_depth : sah_automatic_max_depth(n);
        detail::KdBuildContext ctx(input, config, n);
        ctx.charge(n * sizeof(KdRef));
        std::vector<KdRef> refs(n);  // not zeroed: every element is written here
        detail::for_each_chunk(count, [&](std::size_t c, std::size_t begin, std::size_t end) {
            std::size_t at = first_ref[c];
            for (std::size_t id = begin; id < end; ++id)
                if (!input.bounds[id].empty())
                    refs[at++] = detail::kd_make_ref(static_cast<std::uint32_t>(id), input.bounds[id]);
        });
        Fragment root;
        root.tree = std::move(tree);
        reserve_for(root.tree, n);
        BinnedBuild(ctx, config, root.tree.max_depth).node(std::move(refs), root.tree.bounds, 0, ctx.root_allowance(), root);
        flatten(root);
        tree = std::move(root.tree);
    };
    {
        detail::TsanForkJoin tsan;
        arena.execute(tsan.task(run));
    }
    return tree;
}

}  // namespace kdrt
