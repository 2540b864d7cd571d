// Normal cone test front: refit, ascend and descend (normal_cone_front.h).
#include "collision/normal_cone_front.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>

#include "weft/error.h"

#include "deterministic_parallel.h"

namespace weft::collision {

static_assert(kNone == kNoPatch, "a primitive without a patch must read as never culled in the broad phase");

NormalConeFront::NormalConeFront(const PatchHierarchy& hierarchy) : h_(&hierarchy) {
    const std::size_t nodes = h_->node_size();
    cones_.resize(nodes);
    state_.assign(nodes, kUnknown);
    visit_.assign(nodes, 0);
    if (h_->levels() > 0)
        for (std::uint32_t r = h_->level_first[0]; r < h_->level_first[1]; ++r) front_.push_back(r);
    // No step seen yet: nothing is culled until the first update.
    triangle_patch_.assign(h_->triangle_count, kNone);
    vertex_patch_.assign(h_->vertex_count, kNone);
    edge_patch_.assign(h_->edge_count, kNone);
}

void NormalConeFront::refit(std::span<const Vec3d> x0, std::span<const Vec3d> x1) {
    if (x0.size() != h_->vertex_count || x1.size() != h_->vertex_count)
        throw Error("normal cone front: " + std::to_string(x0.size()) + " start and " + std::to_string(x1.size()) +
                    " end positions for a hierarchy of " + std::to_string(h_->vertex_count) + " vertices");
    x0_ = x0;
    x1_ = x1;
    counters_ = {};
    for (Local& l : local_) l.counters = {};
    const PatchHierarchy& h = *h_;
    // Deepest level first: a node's children sit one level below it. One parallel loop per level
    // (one kernel per level on the device); each node writes only its own cone.
    for (std::size_t level = h.levels(); level-- > 0;) {
        const std::uint32_t first = h.level_first[level], last = h.level_first[level + 1];
        parallel_chunks(last - first, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i) {
                const auto node = static_cast<std::uint32_t>(first + i);
                const std::uint32_t child = h.node_child[node];
                if (child == kNone) {
                    const Triangle& t = h.triangles[h.triangle_order[h.node_first[node]]];
                    cones_[node] =
                        triangle_normal_cone(x0[t.v[0]], x0[t.v[1]], x0[t.v[2]], x1[t.v[0]], x1[t.v[1]], x1[t.v[2]]);
                } else {
                    cones_[node] = merge_cones(cones_[child], cones_[child + 1]);
                }
            }
        });
    }
    counters_.nodes_refit = h.node_size();
    std::fill(state_.begin(), state_.end(), kUnknown);
    if (++epoch_ == 0) {  // wrapped after 2^32 steps: old marks could alias
        std::fill(visit_.begin(), visit_.end(), 0U);
        epoch_ = 1;
    }
}

bool NormalConeFront::passes(std::uint32_t node, ContourTestScratch& scratch, ContourTestCounters& counters) {
    if (state_[node] != kUnknown) return state_[node] == kPass;
    const PatchHierarchy& h = *h_;
    bool ok = true;  // a single triangle cannot collide with itself
    if (!h.is_leaf(node)) {
        ok = (h.node_flags[node] & PatchHierarchy::kDisk) != 0 && cone_is_narrow(cones_[node]) &&
             contour_stays_simple(h.contour(node), cones_[node].axis, x0_, x1_, scratch, counters);
    }
    state_[node] = ok ? kPass : kFail;
    return ok;
}

bool NormalConeFront::node_passes(std::uint32_t node) {
    Local& l = local_.local();
    return passes(node, l.scratch, l.counters);
}

void NormalConeFront::evaluate(std::span<const std::uint32_t> nodes) {
    // Grain 1: a contour test costs from nothing (cone failed) to a few thousand edges.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodes.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          Local& l = local_.local();
                          for (std::size_t i = r.begin(); i != r.end(); ++i)
                              (void)passes(nodes[i], l.scratch, l.counters);
                      });
}

void NormalConeFront::descend() {
    // Level-synchronous: the children of every failing node are evaluated together, those that
    // pass join the front, the others are split further. Subtrees of distinct front nodes are
    // disjoint, so every node is evaluated once and by one thread.
    const PatchHierarchy& h = *h_;
    while (!failing_.empty()) {
        children_.clear();
        for (std::uint32_t n : failing_) {
            children_.push_back(h.node_child[n]);  // a failing node is never a leaf
            children_.push_back(h.node_child[n] + 1);
        }
        evaluate(children_);
        failing_.clear();
        for (std::uint32_t c : children_) (state_[c] == kPass ? next_ : failing_).push_back(c);
    }
}

void NormalConeFront::update(std::span<const Vec3d> x0, std::span<const Vec3d> x1) {
    refit(x0, x1);
    const PatchHierarchy& h = *h_;
    // ---- Ascend: the chains above the front ------------------------------------------------------
    // From each front node up to the first node whose cone fails (no ancestor above it can pass),
    // collecting the nodes that need a contour test; chains merge, so a node walked already ends
    // the walk.
    to_test_.clear();
    for (std::uint32_t f : front_) {
        for (std::uint32_t n = f; n != kNone; n = h.node_parent[n]) {
            if (visit_[n] == epoch_) break;
            visit_[n] = epoch_;
            const bool narrow = cone_is_narrow(cones_[n]);
            if (!h.is_leaf(n) && narrow && (h.node_flags[n] & PatchHierarchy::kDisk) != 0) to_test_.push_back(n);
            if (!narrow) break;
        }
    }
    evaluate(to_test_);
    // The top-most passing node of each chain; all its results are known now, so this runs no test.
    next_.clear();
    failing_.clear();
    Local& l = local_.local();
    for (std::uint32_t f : front_) {
        std::uint32_t top = kNone;
        for (std::uint32_t n = f; n != kNone; n = h.node_parent[n]) {
            if (passes(n, l.scratch, l.counters)) top = n;
            if (!cone_is_narrow(cones_[n])) break;
        }
        if (top == kNone) {
            failing_.push_back(f);
        } else {
            next_.push_back(top);
            if (top != f) ++counters_.ascended;
        }
    }
    counters_.descended = failing_.size();
    // ---- Descend ------------------------------------------------------------------------------------
    descend();
    finish();
}

void NormalConeFront::rebuild(std::span<const Vec3d> x0, std::span<const Vec3d> x1) {
    refit(x0, x1);
    const PatchHierarchy& h = *h_;
    to_test_.clear();
    if (h.levels() > 0)
        for (std::uint32_t r = h.level_first[0]; r < h.level_first[1]; ++r) to_test_.push_back(r);
    evaluate(to_test_);
    next_.clear();
    failing_.clear();
    for (std::uint32_t r : to_test_) (state_[r] == kPass ? next_ : failing_).push_back(r);
    descend();
    finish();
}

void NormalConeFront::finish() {
    const PatchHierarchy& h = *h_;
    std::sort(next_.begin(), next_.end());
    next_.erase(std::unique(next_.begin(), next_.end()), next_.end());
    front_.swap(next_);
    counters_.front_size = front_.size();
    for (std::uint32_t f : front_)
        if (h.is_leaf(f)) ++counters_.single_triangle_patches;
    for (const Local& l : local_) {
        ContourTestCounters& c = counters_.contour;
        c.tests += l.counters.tests;
        c.edges += l.counters.edges;
        c.box_pairs += l.counters.box_pairs;
        c.hull_tests += l.counters.hull_tests;
        c.failed += l.counters.failed;
    }
    // Patch ids: each front node writes its own triangle run (disjoint runs: the front is a cut).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, front_.size(), 16),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                              const std::uint32_t f = front_[i];
                              const std::uint32_t b = h.node_first[f], e = b + h.node_count[f];
                              for (std::uint32_t k = b; k < e; ++k) triangle_patch_[h.triangle_order[k]] = f;
                          }
                      });
    parallel_chunks(h.vertex_count, [&](std::size_t b, std::size_t e) {
        for (std::size_t v = b; v < e; ++v) {
            const std::uint32_t t = h.vertex_triangle[v];
            vertex_patch_[v] = t == kNone ? kNone : triangle_patch_[t];
        }
    });
    parallel_chunks(h.edge_triangle.size(), [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const std::uint32_t t = h.edge_triangle[i];
            edge_patch_[i] = t == kNone ? kNone : triangle_patch_[t];
        }
    });
}

}  // namespace weft::collision
