#pragma once
/// @file
/// The normal cone test front (NCTF; Tang, Liu, Tong & Manocha 2018, "PSCC: parallel self-collision
/// culling with spatial hashing on GPUs"; docs/methods.md §5): per step, the top-most nodes of the
/// `PatchHierarchy` that are provably free of self-collision over the whole step, kept from step to
/// step and updated locally. Each triangle, vertex and edge gets the id of the front node above it
/// (its patch, PSCC's cone id); the broad phase never pairs two primitives of one patch.
///
/// A node passes when it is a single triangle (it cannot collide with itself), or when
///   (a) its continuous normal cone (normal_cone.h, refit bottom-up every step) is narrower than a
///       hemisphere: a direction a exists with a·n(t) > 0 for every triangle normal at every t, and
///   (b) it is a topological disk (patch_hierarchy.h) whose contour, projected along a, has no two
///       non-adjacent edges touching at any t of the step (contour_test.h).
///
/// Why a passing node cannot collide with itself during the step (Volino & Magnenat-Thalmann 1994,
/// "Efficient self-collision detection on smoothly discretized surface animations using geometrical
/// shape regularity"; the argument we rely on, at any fixed t of the step):
///   - By (a), projecting along a maps every triangle of the patch S onto a non-degenerate triangle
///     of the plane with positive orientation.
///   - Count, for a point q of the plane on no projected edge, the triangles whose projection covers
///     q, each with its orientation: all count +1, so the count is m(q), the number of points of S
///     above q. The projected boundary of each triangle winds once around q if it covers q; summing
///     over the triangles, interior edges cancel (their two triangles run them in opposite
///     directions) and m(q) equals the winding number of the projected contour about q.
///   - By (b) the projected contour is a simple polygon: non-adjacent edges never touch, and two
///     adjacent edges cannot overlap either: on a contour of ≥ 4 edges, an overlap of (a,b) and
///     (b,c) puts a or c on the other edge, so the edge before a or after c (non-adjacent to it)
///     touches it too; a 3-edge contour has the signed area of its triangles' sum, > 0. So the
///     winding number is 0 or 1, and m(q) ≤ 1 almost everywhere. Two points of S at one position
///     would, each with the fan of triangles around it (a full disk of positively oriented
///     triangles inside S, a wedge on its contour), cover an open set twice, or put two contour
///     points on one projected point: both are excluded. So S is embedded (injective) at every t.
///   - A vertex v and a triangle T not having v as a corner are disjoint closed subsets of the
///     triangulated disk S, as are two edges sharing no vertex; S embedded keeps their images
///     disjoint at every t of the step: the pair never collides, and CCD of it (at separation 0)
///     reports nothing. The broad phase skips such a pair only when both primitives map to the same
///     front node P; a vertex or edge maps to the node of one fixed incident triangle, so both
///     primitives then lie in P, and the argument applies. Pairs across patches, across cloths, or
///     whose primitives map to different nodes are all kept.
///
/// Thickness. The guarantee above is for contact at distance 0 (the surfaces meeting). Proximity
/// within the contact thickness inside one patch is skipped as well, by design, as in PSCC and
/// Provot 1997: the patch is a single sheet over the projection plane at every instant of the step
/// (injective projection), so no part of it lies over another part of it; two of its non-adjacent
/// primitives come within the thickness only side by side along the surface (the sheet compressed
/// below the thickness between them, or two stretches of the contour close in the plane), where a
/// repulsion would fight the membrane instead of keeping layers apart. The first step in which
/// such parts would pass through one another fails (a) or (b), and then CCD sees them.
///
/// Front maintenance. The front is the cut of the hierarchy made of the top-most passing nodes
/// (a passing node none of whose ancestors passes). Per step, from the previous front:
///   - ascend ("shrinking" in docs/methods.md §5, where passing siblings give way to their parent;
///     some texts call this step sprouting): from each front node walk up while the ancestors' cones
///     pass. A cone that fails fails for every ancestor above it (merged cones only widen), but the
///     contour result is not monotone (a child's own axis may project it worse than its parent's),
///     so every ancestor up to that point is looked at. The top-most passing one replaces all front
///     nodes below it.
///   - descend ("sprouting" in docs/methods.md §5; called shrinking elsewhere): a front node with no
///     passing node on that chain is replaced by the top-most passing nodes of its subtree, found
///     top-down one level at a time. Leaves always pass, so this ends.
/// Both give exactly the top-most passing nodes, the front `rebuild` finds from the roots: a leaf's
/// new front node is either on its old front node's ancestor chain (found by ascending, since no
/// node above the first failing cone can pass) or below it (found by descending).
///
/// Costs: the refit is O(nodes) per step; contour tests run only for the front, the ancestors
/// whose cones pass and, when the front moves down, the subtrees it moves through; contours of
/// front nodes add up to the perimeter of the patches.
///
/// CUDA: refit = one kernel per level (deepest first), a thread per node; ascend = a thread per
/// front node walking up, the contour tests of the distinct nodes met batched one block each
/// (contour_test.h); descend = a frontier kernel per level over a work queue; the patch ids = a
/// thread per triangle reading its front node from a per-triangle "covering node" scatter.

#include <tbb/enumerable_thread_specific.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "weft/types.h"

#include "collision/contour_test.h"
#include "collision/normal_cone.h"
#include "weft/backend/patch_hierarchy.h"

namespace weft::collision {

/// Work of one `update` or `rebuild`.
struct NormalConeFrontCounters {
    std::size_t nodes_refit = 0;              ///< cones computed (every node)
    std::size_t ascended = 0;                 ///< front nodes replaced by an ancestor
    std::size_t descended = 0;                ///< front nodes replaced by descendants
    std::size_t front_size = 0;               ///< nodes on the front after the call
    std::size_t single_triangle_patches = 0;  ///< front nodes that are leaves
    ContourTestCounters contour;              ///< contour tests run
};

/// The front over one hierarchy, kept between steps. Not reentrant (one per thread of control);
/// uses TBB internally, with results that do not depend on the thread count.
class NormalConeFront {
public:
    /// `hierarchy` must outlive the front. The front starts at the roots.
    explicit NormalConeFront(const PatchHierarchy& hierarchy);

    /// Refits the cones for the step x0 → x1 (global positions, the hierarchy's vertex count) and
    /// moves the front to the top-most passing nodes, starting from the previous front. Then the
    /// patch ids below are those of the new front. Throws `weft::Error` for a size mismatch.
    void update(std::span<const Vec3d> x0, std::span<const Vec3d> x1);
    /// The same front computed from the roots, ignoring the previous one (the reference for the
    /// incremental update, and what a first step or a teleport would use).
    void rebuild(std::span<const Vec3d> x0, std::span<const Vec3d> x1);

    /// Front nodes, ascending.
    [[nodiscard]] std::span<const std::uint32_t> front() const { return front_; }
    /// Patch (front node id) of each triangle, vertex and edge, for `BroadPhaseInput`; edges are
    /// indexed like the edge list given to `build_patch_hierarchy`, which must be the broad phase's.
    /// Vertices no triangle uses get kNone (== kNoPatch: never culled), and so does everything
    /// before the first update.
    [[nodiscard]] std::span<const std::uint32_t> triangle_patch() const { return triangle_patch_; }
    [[nodiscard]] std::span<const std::uint32_t> vertex_patch() const { return vertex_patch_; }
    [[nodiscard]] std::span<const std::uint32_t> edge_patch() const { return edge_patch_; }
    /// Whether `node` passes (cone and contour) for the step of the last `update`/`rebuild`,
    /// memoised; for tests and diagnostics (not thread-safe). The positions given to that call must
    /// still be alive and unchanged.
    [[nodiscard]] bool node_passes(std::uint32_t node);
    /// Cone of each node from the last refit.
    [[nodiscard]] const NormalCone& cone(std::uint32_t node) const { return cones_[node]; }
    [[nodiscard]] const NormalConeFrontCounters& counters() const { return counters_; }
    [[nodiscard]] const PatchHierarchy& hierarchy() const { return *h_; }

private:
    enum : std::uint8_t { kUnknown = 0, kPass = 1, kFail = 2 };

    void refit(std::span<const Vec3d> x0, std::span<const Vec3d> x1);
    /// Cone and contour of one node, memoised in state_ for the step; thread-safe for distinct nodes.
    bool passes(std::uint32_t node, ContourTestScratch& scratch, ContourTestCounters& counters);
    /// Evaluates `passes` for every node of `nodes` (distinct) in parallel.
    void evaluate(std::span<const std::uint32_t> nodes);
    /// Moves every node of `failing_` down to the top-most passing nodes of its subtree, appended
    /// to `next_`, one level at a time.
    void descend();
    /// Sorts `next_` into the front and writes the patch ids.
    void finish();

    const PatchHierarchy* h_;
    std::span<const Vec3d> x0_, x1_;  // the step being processed (valid during a call only)
    std::vector<NormalCone> cones_;
    std::vector<std::uint8_t> state_;
    std::vector<std::uint32_t> visit_;  // ascent walk marks: visit_[n] == epoch_ once walked this step
    std::uint32_t epoch_ = 0;
    std::vector<std::uint32_t> front_, next_, to_test_, failing_, children_;
    std::vector<std::uint32_t> triangle_patch_, vertex_patch_, edge_patch_;
    NormalConeFrontCounters counters_;
    struct Local {
        ContourTestScratch scratch;
        ContourTestCounters counters;
    };
    tbb::enumerable_thread_specific<Local> local_;
};

}  // namespace weft::collision
