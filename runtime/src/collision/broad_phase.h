#pragma once
/// @file
/// CPU reference broad phase for cloth collisions: a sorted spatial hash (Teschner et al. 2003;
/// docs/methods.md §4) over the swept, thickness-inflated bounds of vertices, edges and triangles. It
/// returns every vertex–face and edge–edge pair whose bounds overlap, minus topologically adjacent
/// ones, as sorted unique lists that are bit-identical on any thread count. The narrow phase
/// (proximity and CCD) and the GPU broad phase are checked against this.

#include <tbb/enumerable_thread_specific.h>

#include <compare>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "weft/backend/collision_primitives.h"
#include "weft/types.h"

namespace weft::collision {

/// What the broad phase looks at. The spans must stay valid for the call only.
struct BroadPhaseInput {
    std::span<const Vec3d> x0;            ///< positions at the start of the step, m
    std::span<const Vec3d> x1;            ///< positions at the end of the step (same size as x0), m
    std::span<const Triangle> triangles;  ///< global vertex ids
    std::span<const Edge> edges;          ///< unique edges, normally `build_edges(triangles)`
    /// Cloth of each triangle (optional: empty means one cloth). Only read when `self_pairs` is
    /// false; a vertex or edge takes the cloth of a triangle it belongs to.
    std::span<const std::uint32_t> triangle_cloth;
    /// Every bound (vertex, edge, triangle) is grown by this much on each side, m; two primitives
    /// therefore pair when they come within 2·thickness of each other along every axis.
    double thickness = 0.0;
    /// Hash cell edge, m. 0 picks the median extent (longest axis) of the edges' bounds, a robust
    /// average edge length that includes the motion and the thickness (docs/methods.md §4: cells about
    /// as large as the primitives keep both the entries per primitive and the occupants per cell
    /// small).
    double cell_size = 0.0;
    /// The bounds are taken in a frame that moves by this much over the step (each x1 read as
    /// x1 − frame_motion), m. Whether two primitives come close depends only on their relative
    /// motion, which a common translation does not change, so the pairs are the same superset of
    /// every pair that comes within 2·thickness at some time of the step; what shrinks is the
    /// false candidates of a common motion (a stack of sheets falling together, a running body and
    /// its cape). 0: the world frame.
    Vec3d frame_motion{};
    /// Triangle groups (`triangle_cloth`) from this id on are kinematic: mesh colliders, moved as
    /// prescribed. A pair whose two primitives both lie in such groups is never a candidate (nothing
    /// in it can move, so no later stage can use it): a body mesh's pairs with itself are skipped.
    /// Needs `triangle_cloth`; the largest value (default) marks no group kinematic.
    std::uint32_t first_kinematic_group = std::numeric_limits<std::uint32_t>::max();
    /// Extra growth per vertex, m (optional: empty, or one entry per vertex, each finite and ≥ 0). A
    /// vertex's bound grows by thickness + its padding; an edge's or triangle's by thickness + the
    /// largest padding of its vertices. So two primitives within max(p_a, p_b) of each other always
    /// pair, p being each one's padding: the per-vertex query radii of the displacement bounds.
    std::span<const double> vertex_padding;
    /// Pairs within one cloth. Always true for now; false keeps cloth–cloth pairs only.
    bool self_pairs = true;
    /// Self-collision culling (docs/methods.md §5; PSCC's cone ids), optional: either all three empty
    /// (no culling) or sized like the vertices, edges and triangles. The patch id of each primitive,
    /// normally `NormalConeFront`'s: a pair whose two primitives carry the same id (other than
    /// kNoPatch) is never generated, because the patch is proven free of self-collision over the
    /// step (normal_cone_front.h says why skipping it is conservative). Within a cell the occupants
    /// are grouped by (kind, patch, index) — the cell key extended with the cone id — and only
    /// pairs across groups are formed.
    std::span<const std::uint32_t> vertex_patch;
    std::span<const std::uint32_t> edge_patch;
    std::span<const std::uint32_t> triangle_patch;
    /// With culling, also count the pairs it removed (`BroadPhaseCounters::culled_pairs`) by testing
    /// their bounds, without emitting them. false skips them untested and leaves the count at 0.
    bool count_culled = true;
    /// Optional, one flag per vertex (or empty: every pair): only pairs with at least one vertex
    /// flagged are candidates. A later detection round of the impact zones flags the vertices that
    /// moved since the last round (and those of its hits): a pair whose four vertices all stayed put
    /// was tested then and missed, or could not collide, and would miss again, so it is not worth
    /// forming. Cells with no flagged occupant are skipped whole.
    std::span<const std::uint8_t> vertex_changed;
};

/// Work counters of one call (for the step statistics, issue 4 item 8).
struct BroadPhaseCounters {
    double cell_size = 0.0;            ///< cell edge used, m
    std::size_t primitives = 0;        ///< vertices + edges + triangles with finite bounds
    std::size_t nonfinite = 0;         ///< primitives skipped because a position is NaN or infinite
    std::size_t oversized = 0;         ///< primitives too large to hash, tested against all partners
    std::size_t entries = 0;           ///< (cell, primitive) entries hashed
    std::size_t cells_occupied = 0;    ///< distinct cells holding at least one entry
    std::size_t max_cell_entries = 0;  ///< occupants of the fullest cell
    std::size_t tested_pairs = 0;      ///< compatible pairs sharing a cell, counted once per shared cell
    std::size_t candidate_pairs = 0;   ///< of those, overlapping and not adjacent: output before dedup
    std::size_t vf_pairs = 0;          ///< vertex–face pairs out
    std::size_t ee_pairs = 0;          ///< edge–edge pairs out
    /// Same-patch pairs that culling removed and that would otherwise have been candidates, counted
    /// like `candidate_pairs` (once per shared cell, before dedup): the candidates without culling
    /// are candidate_pairs + culled_pairs. 0 without culling or with `count_culled` false. Not
    /// included in `tested_pairs`.
    std::size_t culled_pairs = 0;
};

/// Output of one call: sorted, unique pair lists and the counters.
struct BroadPhaseResult {
    std::vector<VertexFacePair> vf;
    std::vector<EdgeEdgePair> ee;
    BroadPhaseCounters counters;
};

/// The spatial hash. Keeps its scratch between calls so that a step does not allocate once sizes
/// have settled; one object per thread of control (`find` is not reentrant).
class BroadPhase {
public:
    /// Fills `out` with every vertex–face pair (v, t) whose bounds overlap where v is not a corner
    /// of t, and every edge–edge pair whose bounds overlap where the edges share no vertex. A bound
    /// is the box around the primitive's vertices at x0 and x1, grown by the thickness. Primitives
    /// with a non-finite position (or a bound that overflows) are skipped and counted. Throws
    /// `weft::Error` for mismatched sizes, out-of-range indices or a negative thickness or cell size.
    void find(const BroadPhaseInput& in, BroadPhaseResult& out);

    /// Fills `out` with what `find(in, out)` gives, reusing the pairs `earlier` (another broad phase)
    /// wrote into `earlier_pairs` in its last `find`. A vertex whose bound now lies inside that
    /// call's bound of it is "inside"; an edge or triangle whose vertices are all inside has its bound
    /// inside that call's too (a union of theirs), so a pair of two such primitives whose bounds
    /// overlap now overlapped then and is among `earlier_pairs`: those are kept where their bounds
    /// still overlap and `in`'s culling keeps them. The pairs with a vertex outside are hashed on
    /// their own (as with `vertex_changed`), and the two sorted lists merged: the same lists, in the
    /// same order, as `find(in)`. Returns true where it reused; false where it called `find` instead:
    /// the earlier call culled, padded or took only changed vertices, or had other topology or cloth
    /// filters; `in` pads, takes only changed vertices or counts culled pairs; or more than one
    /// vertex in kReuseOutsideShare is outside. The counters: `tested_pairs` adds the earlier pairs
    /// looked at, `candidate_pairs` those kept. The CPU's impact zones answer their first detection
    /// of a substep from the proximity detection's pairs: their bounds are grown by eta, the
    /// proximity's by the contact thickness, around the motion the solve mostly kept.
    bool find_reusing(BroadPhase& earlier, const BroadPhaseResult& earlier_pairs, const BroadPhaseInput& in,
                      BroadPhaseResult& out);
    /// find_reusing hashes everything anew when more than one vertex in this many lies outside.
    static constexpr std::size_t kReuseOutsideShare = 4;

    /// Bytes of scratch the hash keeps between calls (its own buffers and every thread's pair lists).
    /// Every kTrimPeriod calls (buffer_trim.h) the pair lists, and `out`'s, that stayed far larger than
    /// what those calls found are cut back: one frame's flood of pairs is not kept for the whole run.
    [[nodiscard]] std::size_t scratch_bytes() const;

    /// A primitive overlapping more cells than this is not hashed but tested against every partner
    /// directly, so that one exploding vertex cannot flood the hash (the result is the same).
    static constexpr std::uint64_t kMaxCellsPerPrimitive = 512;

private:
    struct Box {
        Vec3d lo, hi;
    };
    struct Entry {
        std::uint64_t cell;  // packed cell coordinates (exact, so different cells never share a key)
        std::uint32_t prim;
    };
    // Pairs and counters one thread found; merged and sorted at the end, so the thread count and
    // the order the work ran in do not show in the result.
    struct Local {
        std::vector<VertexFacePair> vf;
        std::vector<EdgeEdgePair> ee;
        std::size_t tested = 0;
        std::size_t candidates = 0;
        std::size_t culled = 0;
        std::size_t vf_peak = 0, ee_peak = 0;  // the largest lists of the trim window
        // The current cell's occupants.
        std::vector<std::uint32_t> prim;
        std::vector<Box> box;
        std::vector<std::uint64_t> cell_lo;
        // With culling: the occupants grouped by (kind, patch, index).
        struct Occupant {
            Box box;
            std::uint64_t cell_lo;
            std::uint32_t prim, patch;
        };
        std::vector<Occupant> occ;
    };

    // Primitives live in one index space: vertices [0, n), edges [n, n+E), triangles [n+E, n+E+T).
    std::vector<Box> box_;
    std::vector<std::uint64_t> cell_lo_, cell_hi_;  // packed cell coordinates of each bound's corners
    std::vector<std::size_t> offset_;               // first entry of each primitive (size P+1)
    std::vector<std::uint32_t> oversized_;
    std::vector<std::uint32_t> vertex_cloth_;
    std::vector<Entry> entries_, sorted_;  // sorted_: the radix sort's other buffer
    std::vector<VertexFacePair> vf_scratch_;  // the pair lists' radix sort buffers
    std::vector<EdgeEdgePair> ee_scratch_;
    std::vector<std::size_t> histogram_;   // radix sort: bucket counts, then offsets, per chunk
    std::vector<std::size_t> cell_start_;
    std::vector<double> extent_;       // edge bound extents, for the automatic cell size
    std::vector<std::uint8_t> state_;  // per primitive: hashed, non-finite or oversized
    std::vector<std::uint8_t> changed_;  // per primitive, with BroadPhaseInput::vertex_changed: a vertex of it is flagged
    std::vector<std::uint8_t> needed_;   // per primitive, with vertex_changed: hashed this call (not an unchanged one far from a change)
    std::vector<std::uint8_t> region_;   // the coarse cells the changed primitives' bounds cover
    tbb::enumerable_thread_specific<Local> local_;
    // What clean_pairs_within_last needs to know of the last find (box_ keeps that call's bounds).
    struct LastCall {
        bool reusable = false;  // no culling, padding or changed-vertex filter left any pair out
        std::size_t n = 0;
        std::span<const Triangle> triangles;
        std::span<const Edge> edges;
        std::span<const std::uint32_t> triangle_cloth;
        bool self_pairs = true;
        std::uint32_t first_kinematic_group = 0;
        const BroadPhaseResult* result = nullptr;  // where it wrote its pairs
        std::size_t vf = 0, ee = 0;                // and how many
    };
    LastCall last_;
    std::vector<Box> within_box_;        // clean_pairs_within_last: the new bounds of every primitive
    std::vector<std::uint8_t> keep_;     // clean_pairs_within_last: which of the last pairs stay
    BroadPhaseResult reuse_clean_, reuse_moved_;  // find_reusing: the two lists it merges
    std::vector<std::uint8_t> reuse_outside_;     // find_reusing: the vertices outside the earlier bounds
    /// On the earlier broad phase: the pairs of its last result `last` (at `&last`) between primitives
    /// whose vertices all lie inside its bounds, where they still overlap under `in`, into `clean`,
    /// and the vertices outside into `outside`. False where the last call cannot be reused.
    bool clean_pairs_within_last(const BroadPhaseInput& in, const BroadPhaseResult& last, BroadPhaseResult& clean,
                                 std::vector<std::uint8_t>& outside);
    // The trim window (buffer_trim.h): calls since the last trim, and the largest merged lists.
    std::size_t calls_since_trim_ = 0;
    std::size_t out_vf_peak_ = 0, out_ee_peak_ = 0;
    /// Notes this call's list sizes and, at the end of a window, cuts the oversized lists back.
    void trim_pair_lists(BroadPhaseResult& out);
};

}  // namespace weft::collision
