// SAH kd-tree builder in O(N log N), after I. Wald and V. Havran, "On building
// fast kd-Trees for Ray Tracing, and on doing that in O(N log N)", IEEE
// Symposium on Interactive Ray Tracing 2006:
//  - each object contributes, per axis, a start and an end event (or one
//    planar event when it is flat on that axis); the three per-axis lists are
//    sorted once at the root (by position, then end < planar < start) and kept
//    sorted through every split: the events of objects that stay on one side
//    are filtered in order, and only the objects straddling the plane are
//    clipped to the two child cells ("perfect splits", with input.clip when it
//    is set), their new events sorted and merged in;
//  - one sweep per axis evaluates every event position strictly inside the
//    cell, with the objects lying in the plane put on the cheaper side;
//  - cost model below, with the empty-space bonus; a node becomes a leaf when
//    the best split does not beat the leaf cost, or at the depth limit
//    (automatic: 8 + 1.3 log2 N, the rule of thumb of pbrt's kd-tree).
// What we changed: the event positions are rounded outward to floats once
// (lower bounds down, upper bounds up), so every candidate plane is a float and
// the stored float split classifies the objects exactly as the builder did.
// Objects are costed per type (KdBuildContext: sphere and triangle tests in
// fixed-point units of a node step), and a split must fit the node's
// duplication allowance. Events carry numbers local to the build, so the
// binned builder runs one such exact build per small subtree, on any thread.
// Memory: a node's event lists become its below child's (filtered in place,
// the straddlers' new events merged in from the back), so a build holds about
// the root's events plus the above-child lists pending on the current path.
#include "kdtree/sah_kd_builder.h"

#include "kdtree/kd_build_common.h"

#include <kdrt/error.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace kdrt {

namespace {

// Event types in their order at equal positions: objects ending at p are
// already behind the plane when objects starting at p are counted in front.
enum EventType : std::uint32_t { kEnd = 0, kPlanar = 1, kStart = 2 };

// 8 bytes: the object id in the low 30 bits, the type in the top 2.
constexpr std::uint32_t kMaxObjects = std::uint32_t{1} << 30;

struct Event {
    float pos;
    std::uint32_t bits;

    Event() = default;
    Event(float p, std::uint32_t id, EventType type) : pos(p), bits(id | (std::uint32_t{type} << 30)) {}
    std::uint32_t id() const { return bits & (kMaxObjects - 1); }
    std::uint32_t type() const { return bits >> 30; }
};

// Sort key: the position's bits mapped to an unsigned order (negative floats
// reversed), then the type. Positions are never NaN, and -0 is stored as +0.
inline std::uint64_t sort_key(const Event& e) {
    const auto u = std::bit_cast<std::uint32_t>(e.pos);
    const std::uint32_t ordered = (u & 0x80000000u) ? ~u : (u | 0x80000000u);
    return (std::uint64_t{ordered} << 2) | e.type();
}
bool operator<(const Event& a, const Event& b) { return sort_key(a) < sort_key(b); }

using Events = std::array<std::vector<Event>, 3>;  // one sorted list per axis

// Adds the events of box b (inside the cell, double bounds) rounded outward to
// floats. The cell's faces are floats, so the rounded box stays in the cell.
void add_events(Events& events, std::uint32_t id, const Aabb& b) {
    for (int k = 0; k < 3; ++k) {
        const float lo = detail::round_down_to_float(b.lo[k]) + 0.0f;  // + 0.0f turns -0 into +0
        const float hi = detail::round_up_to_float(b.hi[k]) + 0.0f;
        if (lo == hi) {
            events[k].emplace_back(lo, id, kPlanar);
        } else {
            events[k].emplace_back(lo, id, kStart);
            events[k].emplace_back(hi, id, kEnd);
        }
    }
}

// Merges the sorted `extra` into the sorted `list`, from the back, in place.
void merge_from_back(std::vector<Event>& list, const std::vector<Event>& extra) {
    if (extra.empty()) return;
    std::size_t i = list.size(), j = extra.size(), out = list.size() + extra.size();
    list.resize(out);
    while (j > 0) {
        if (i > 0 && extra[j - 1] < list[i - 1]) list[--out] = list[--i];
        else list[--out] = extra[--j];
    }
}

enum Side : std::uint8_t { kBelow, kAbove, kBoth };

struct Split {
    int axis = -1;
    float pos = 0.0f;
    bool planar_below = true;  // where the objects lying in the plane go
    double cost = std::numeric_limits<double>::infinity();
};

// One exact build over a set of objects, numbered locally 0..n-1 (events
// carry local numbers, so the scratch is sized by the set, not the scene: the
// binned builder runs one per small subtree, on any thread).
class SahBuild {
public:
    SahBuild(detail::KdBuildContext& ctx, int max_depth, double bonus_factor, std::vector<std::uint32_t> ids,
             KdTree& tree)
        : ctx_(ctx),
          max_depth_(max_depth),
          bonus_factor_(bonus_factor),
          tree_(tree),
          ids_(std::move(ids)),
          side_(ids_.size(), kBoth) {
        weights_.reserve(ids_.size());
        for (std::uint32_t id : ids_) weights_.push_back(ctx.weight(id));
        uniform_weight_ = weights_.empty() ? 1 : weights_[0];
        for (std::uint64_t w : weights_)
            if (w != uniform_weight_) uniform_weight_ = 0;
    }

    std::uint64_t weight_of(const std::vector<Event>& x_events) const {
        std::uint64_t w = 0;
        for (const Event& x : x_events)
            if (x.type() != kEnd) w += weights_[x.id()];
        return w;
    }

    // n: the objects in the node, w: their summed weights.
    void node(Events events, std::size_t n, std::uint64_t w, const Aabb& cell, int depth, double allowance) {
        ctx_.check_cancelled();
        Split split;
        if (n > 0 && depth < max_depth_) split = find_split(events, w, cell);
        const double leaf_cost = static_cast<double>(w);
        if (split.axis < 0 || split.cost >= leaf_cost) {
            emit_leaf(events[0], allowance);
            return;
        }

        const int axis = split.axis;
        Aabb below_cell = cell, above_cell = cell;
        below_cell.hi[axis] = split.pos;
        above_cell.lo[axis] = split.pos;
        std::size_t only_below = 0, only_above = 0;
        classify(events[axis], split, only_below, only_above);
        // Bounded duplication: the children may hold at most the node's allowance.
        if (static_cast<double>(only_below + only_above + 2 * straddlers_.size()) > allowance) {
            emit_leaf(events[0], allowance);
            return;
        }
        Events above;
        std::size_t n_below = 0, n_above = 0;
        const std::size_t event_bytes = (events[0].size() + events[1].size() + events[2].size()) * sizeof(Event);
        ctx_.charge(event_bytes);  // the above lists, at most as long as the node's
        distribute(events, above, only_below, only_above, cell, split, n_below, n_above);  // events -> below
        const std::uint64_t w_below = weight_of(events[0]), w_above = weight_of(above[0]);
        const double share = allowance / static_cast<double>(std::max<std::size_t>(n_below + n_above, 1));

        const std::size_t index = tree_.nodes.size();
        tree_.nodes.emplace_back();
        node(std::move(events), n_below, w_below, below_cell, depth + 1, share * static_cast<double>(n_below));
        const auto above_index = static_cast<std::uint32_t>(
            std::min<std::size_t>(tree_.nodes.size(), std::numeric_limits<std::uint32_t>::max()));
        tree_.nodes[index] = kd_make_inner(axis, split.pos, above_index);  // throws if the index does not fit
        node(std::move(above), n_above, w_above, above_cell, depth + 1, share * static_cast<double>(n_above));
        ctx_.release(event_bytes);
    }

private:
    // Expected cost of a split, in fixed-point units of one node step (the
    // weights carry the per-object intersection costs, KdBuildContext):
    //   C = C_step + SA_L/SA * W_L + SA_R/SA * W_R
    // SA_x/SA is the probability that a ray entering the cell also enters the
    // child (uniformly distributed rays), W_x the child's summed object costs.
    // A split cutting off empty space is rewarded: C *= 1 - empty_bonus.
    double cost(double p_below, double p_above, std::uint64_t w_below, std::uint64_t w_above) const {
        double c = ctx_.traversal_cost() + p_below * static_cast<double>(w_below) + p_above * static_cast<double>(w_above);
        return (w_below == 0 || w_above == 0) ? c * bonus_factor_ : c;
    }

    // One sweep per axis over the sorted events (Wald-Havran's FindPlane).
    Split find_split(const Events& events, std::uint64_t total, const Aabb& cell) const {
        const bool counted = uniform_weight_ != 0 && std::max({events[0].size(), events[1].size(), events[2].size()}) <
                                                        (std::size_t{1} << 21);
        return counted ? find_split_with<true>(events, total, cell) : find_split_with<false>(events, total, cell);
    }

    // Uniform: every object costs uniform_weight_ (a mesh without spheres), so
    // the sweep counts the events at each position in one word, 21 bits per
    // type (a list shorter than 2^21 events cannot overflow a field), and
    // scales the counts by the weight: the same integer sums as summing
    // weights, so the same tree, without a per-object lookup.
    template <bool Uniform>
    Split find_split_with(const Events& events, std::uint64_t total, const Aabb& cell) const {
        Split best;
        const double area = cell.surface_area();
        if (!(area > 0.0)) return best;
        const double inv_area = 1.0 / area;
        const glm::dvec3 d = cell.extent();
        constexpr std::uint64_t kField = (std::uint64_t{1} << 21) - 1;
        for (int k = 0; k < 3; ++k) {
            const double lo = cell.lo[k], hi = cell.hi[k];
            const double cross = d[(k + 1) % 3] * d[(k + 2) % 3];
            const double perimeter = d[(k + 1) % 3] + d[(k + 2) % 3];
            const std::vector<Event>& e = events[k];
            const std::size_t n = e.size();
            std::uint64_t w_below = 0, w_above = total;
            std::uint64_t packed = 0;                         // Uniform: event counts by type
            std::uint64_t ends = 0, planars = 0, starts = 0;  // weights at the current position
            // Per event, summing by type without branching (the types are
            // unpredictable); the work happens once the position changes.
            for (std::size_t i = 0; i < n; ++i) {
                const std::uint32_t type = e[i].type();
                if constexpr (Uniform) {
                    packed += std::uint64_t{1} << (21 * type);
                } else {
                    const std::uint64_t w = weights_[e[i].id()];
                    ends += (type == kEnd) * w;
                    planars += (type == kPlanar) * w;
                    starts += (type == kStart) * w;
                }
                const float p = e[i].pos;
                if (i + 1 < n && e[i + 1].pos == p) continue;
                if constexpr (Uniform) {
                    ends = (packed & kField) * uniform_weight_;
                    planars = ((packed >> 21) & kField) * uniform_weight_;
                    starts = (packed >> 42) * uniform_weight_;
                    packed = 0;
                }
                w_above -= ends + planars;
                if (lo < p && p < hi) {  // never on the cell's boundary
                    const double p_below = 2.0 * (cross + (p - lo) * perimeter) * inv_area;
                    const double p_above = 2.0 * (cross + (hi - p) * perimeter) * inv_area;
                    const double with_below = cost(p_below, p_above, w_below + planars, w_above);
                    if (with_below < best.cost) best = {k, p, true, with_below};
                    if (planars > 0) {
                        const double with_above = cost(p_below, p_above, w_below, w_above + planars);
                        if (with_above < best.cost) best = {k, p, false, with_above};
                    }
                }
                w_below += starts + planars;
                ends = planars = starts = 0;
            }
        }
        return best;
    }

    // Classifies the objects against the split (Wald-Havran's
    // ClassifyLeftRightBoth) in one pass over the split axis' events: a start
    // is always met before its end, so an object straddles when its start lies
    // before the plane and its end after it. Each object is counted once.
    void classify(const std::vector<Event>& e, const Split& split, std::size_t& only_below, std::size_t& only_above) {
        const float p = split.pos;
        straddlers_.clear();
        only_below = only_above = 0;
        for (const Event& x : e) {
            const std::uint32_t id = x.id();
            switch (x.type()) {
                case kStart:
                    if (x.pos >= p) {
                        side_[id] = kAbove;
                        ++only_above;
                    } else {
                        side_[id] = kBoth;
                    }
                    break;
                case kEnd:
                    if (x.pos <= p) {
                        side_[id] = kBelow;
                        ++only_below;
                    } else if (side_[id] == kBoth) {
                        straddlers_.push_back(id);
                    }
                    break;
                default:  // planar
                    if (x.pos < p || (x.pos == p && split.planar_below)) {
                        side_[id] = kBelow;
                        ++only_below;
                    } else {
                        side_[id] = kAbove;
                        ++only_above;
                    }
                    break;
            }
        }
    }

    // Splits the classified, sorted event lists (events becomes the below
    // child's, in place) and merges in the straddlers' clipped events.
    void distribute(Events& events, Events& above, std::size_t only_below, std::size_t only_above, const Aabb& cell,
                    const Split& split, std::size_t& n_below, std::size_t& n_above) {
        Aabb below_cell = cell, above_cell = cell;
        below_cell.hi[split.axis] = split.pos;
        above_cell.lo[split.axis] = split.pos;
        for (int k = 0; k < 3; ++k) {
            // Each event is written to both outputs and kept where it belongs
            // (branch-free: the sides are unpredictable off the split axis).
            // The below list is filtered in place (written <= read position);
            // the above list has room for every above event plus one.
            std::vector<Event>& list = events[k];
            std::vector<Event>& up = above[k];
            up.resize(std::min(list.size(), 2 * (only_above + straddlers_.size())) + 1);
            std::size_t kept = 0, lifted = 0;
            for (std::size_t i = 0; i < list.size(); ++i) {
                const Event x = list[i];
                const std::uint8_t s = side_[x.id()];
                list[kept] = x;
                up[lifted] = x;
                kept += s == kBelow;
                lifted += s == kAbove;
            }
            list.erase(list.begin() + static_cast<std::ptrdiff_t>(kept), list.end());
            up.erase(up.begin() + static_cast<std::ptrdiff_t>(lifted), up.end());
        }

        // Perfect splits: the straddlers' events are regenerated from their
        // parts inside each child cell, which may leave them on one side only.
        for (int k = 0; k < 3; ++k) {
            new_below_[k].clear();
            new_above_[k].clear();
        }
        n_below = only_below;
        n_above = only_above;
        for (std::uint32_t local : straddlers_) {
            const std::uint32_t id = ids_[local];
            Aabb b, a;
            detail::kd_split_object(ctx_.input, id, cell, split.axis, split.pos, b, a);
            if (b.empty() && a.empty()) {  // a clip function disagreeing with the bounds: stay conservative
                b = ctx_.input.bounds[id].intersect(below_cell);
                a = ctx_.input.bounds[id].intersect(above_cell);
            }
            if (!b.empty()) {
                add_events(new_below_, local, b);
                ++n_below;
            }
            if (!a.empty()) {
                add_events(new_above_, local, a);
                ++n_above;
            }
        }
        for (int k = 0; k < 3; ++k) {
            std::sort(new_below_[k].begin(), new_below_[k].end());
            std::sort(new_above_[k].begin(), new_above_[k].end());
            merge_from_back(events[k], new_below_[k]);
            merge_from_back(above[k], new_above_[k]);
        }
    }

    // Every object has exactly one start or planar event per axis.
    void emit_leaf(const std::vector<Event>& x_events, double allowance) {
        leaf_ids_.clear();
        for (const Event& x : x_events)
            if (x.type() != kEnd) leaf_ids_.push_back(ids_[x.id()]);
        std::sort(leaf_ids_.begin(), leaf_ids_.end());
        ctx_.charge(detail::KdBuildContext::leaf_bytes(leaf_ids_.size()));
        detail::kd_emit_leaf(tree_, leaf_ids_);
        ctx_.leaf_done(allowance);
    }

    detail::KdBuildContext& ctx_;
    int max_depth_;
    double bonus_factor_;
    KdTree& tree_;
    std::vector<std::uint32_t> ids_;       // local number -> object id
    std::vector<std::uint64_t> weights_;  // local number -> intersection cost
    std::uint64_t uniform_weight_ = 0;    // every object's weight when they are all equal, else 0
    // Scratch, reused by every node (none of it lives across a recursion).
    std::vector<std::uint8_t> side_;  // per local number
    std::vector<std::uint32_t> straddlers_, leaf_ids_;
    Events new_below_, new_above_;
};

}  // namespace

int detail::sah_automatic_max_depth(std::size_t n) {
    const double depth = 8.0 + 1.3 * std::log2(static_cast<double>(std::max<std::size_t>(n, 1)));
    return static_cast<int>(std::min(64L, std::lround(depth)));
}

KdTree detail::build_exact_sah_kd_tree(const KdBuildInput& input, const KdBuildConfig& config) {
    if (input.bounds.size() > kMaxObjects)
        throw Error(ErrorCode::Unsupported, "SAH kd-tree builder: " + std::to_string(input.bounds.size()) +
                                                " objects, at most 2^30 are supported");
    KdTree tree;
    tree.bounds = detail::kd_root_cell(input);
    tree.object_count = static_cast<std::uint32_t>(input.bounds.size());

    std::vector<std::uint32_t> ids;
    for (std::uint32_t id = 0; id < tree.object_count; ++id)
        if (!input.bounds[id].empty()) ids.push_back(id);
    const std::size_t n = ids.size();
    tree.max_depth = config.max_depth > 0 ? config.max_depth : sah_automatic_max_depth(n);
    detail::KdBuildContext ctx(input, config, n);
    ctx.charge(n * 6 * sizeof(Event));

    Events events;
    for (auto& list : events) list.reserve(2 * n);
    for (std::uint32_t local = 0; local < n; ++local) add_events(events, local, input.bounds[ids[local]]);
    for (auto& list : events) std::sort(list.begin(), list.end());

    SahBuild build(ctx, tree.max_depth, 1.0 - config.empty_bonus, std::move(ids), tree);
    const std::uint64_t w = build.weight_of(events[0]);
    build.node(std::move(events), n, w, tree.bounds, 0, ctx.root_allowance());
    return tree;
}

namespace detail {

void build_exact_sah_subtree(KdBuildContext& ctx, int max_depth, double empty_bonus, std::span<const KdRef> refs,
                             const Aabb& cell, int depth, double allowance, KdTree& out) {
    std::vector<std::uint32_t> ids;
    ids.reserve(refs.size());
    Events events;
    for (auto& list : events) list.reserve(2 * refs.size());
    for (const KdRef& r : refs) {
        const auto local = static_cast<std::uint32_t>(ids.size());
        ids.push_back(r.id);
        for (int k = 0; k < 3; ++k) {
            if (r.lo[k] == r.hi[k]) {
                events[k].emplace_back(r.lo[k], local, kPlanar);
            } else {
                events[k].emplace_back(r.lo[k], local, kStart);
                events[k].emplace_back(r.hi[k], local, kEnd);
            }
        }
    }
    for (auto& list : events) std::sort(list.begin(), list.end());
    const std::size_t bytes = refs.size() * 6 * sizeof(Event);
    ctx.charge(bytes);
    SahBuild build(ctx, max_depth, 1.0 - empty_bonus, std::move(ids), out);
    const std::uint64_t w = build.weight_of(events[0]);
    build.node(std::move(events), refs.size(), w, cell, depth, allowance);
    ctx.release(bytes);
}

}  // namespace detail

}  // namespace kdrt
