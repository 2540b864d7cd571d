// One part of a partitioned world as a model of its own (weft/backend/part_model.h).
#include "weft/backend/part_model.h"

#include <limits>
#include <string>

#include "weft/error.h"

namespace weft {
namespace {

constexpr std::uint32_t kAbsent = std::numeric_limits<std::uint32_t>::max();

}  // namespace

PartModel extract_part(const FlatModel& flat, const VertexPartition& partition, std::uint32_t p, bool per_triangle_bending) {
    if (p >= partition.parts)
        throw Error("extract_part: part " + std::to_string(p) + " of " + std::to_string(partition.parts));
    if (partition.part_of.size() != flat.vertex_count)
        throw Error("extract_part: a partition of " + std::to_string(partition.part_of.size()) + " vertices for a model of " +
                    std::to_string(flat.vertex_count));
    const PartitionPart& part = partition.part[p];
    const BlockPattern& gp = flat.pattern;
    PartModel out;
    FlatModel& m = out.model;
    out.owned = static_cast<std::uint32_t>(part.owned.size());
    out.interior = part.interior;

    // Local vertices: owned, then ghosts.
    out.global_vertex = part.owned;
    out.global_vertex.insert(out.global_vertex.end(), part.ghosts.begin(), part.ghosts.end());
    const std::size_t n = out.global_vertex.size();
    std::vector<std::uint32_t> local(flat.vertex_count, kAbsent);
    for (std::size_t i = 0; i < n; ++i) local[out.global_vertex[i]] = static_cast<std::uint32_t>(i);
    m.vertex_count = n;
    m.initial_positions.reserve(n);
    m.initial_velocities.reserve(n);
    m.mass.reserve(n);
    m.vertex_cloth.reserve(n);
    for (const std::uint32_t g : out.global_vertex) {
        m.initial_positions.push_back(flat.initial_positions[g]);
        m.initial_velocities.push_back(flat.initial_velocities[g]);
        m.mass.push_back(flat.mass[g]);
        m.vertex_cloth.push_back(flat.vertex_cloth[g]);
    }

    // Elements touching an owned vertex, in global order; every one of their vertices is local.
    const auto touches_owned = [&](const auto& vertices) {
        for (const std::uint32_t v : vertices)
            if (local[v] != kAbsent && local[v] < out.owned) return true;
        return false;
    };
    const auto to_local = [&](auto element, const char* what, std::size_t index) {
        for (auto& v : element.v) {
            if (local[v] == kAbsent)
                throw Error(std::string("extract_part: ") + what + " " + std::to_string(index) + " has vertex " +
                            std::to_string(v) + ", neither owned by part " + std::to_string(p) +
                            " nor one of its ghosts (a partition of another pattern, or per-triangle bending on a partition "
                            "built without its reach?)");
            v = local[v];
        }
        return element;
    };
    std::vector<std::uint8_t> triangle_in(flat.triangles.size(), 0), hinge_in(flat.hinges.size(), 0);
    for (std::size_t t = 0; t < flat.triangles.size(); ++t) triangle_in[t] = touches_owned(flat.triangles[t].v) ? 1 : 0;
    for (std::size_t h = 0; h < flat.hinges.size(); ++h) hinge_in[h] = touches_owned(flat.hinges[h].v) ? 1 : 0;
    if (per_triangle_bending) {
        // A hinge through an owned vertex takes terms from both its faces, and each face's terms read
        // its three hinges (weft/physics/shell_bending_slots.h): those faces and hinges come too. The
        // extra ones touch ghosts only, so what they assemble lands in ghost rows, which no part solves.
        if (flat.triangle_hinges.size() != flat.triangles.size() || flat.shell_rest.size() != flat.triangles.size())
            throw Error("extract_part: the model has no per-triangle bending data");
        for (std::size_t t = 0; t < flat.triangles.size(); ++t)
            for (const std::int32_t h : flat.triangle_hinges[t].edge)
                if (h >= 0 && hinge_in[static_cast<std::size_t>(h)] == 1) triangle_in[t] = 1;
        for (std::size_t t = 0; t < flat.triangles.size(); ++t)
            if (triangle_in[t] != 0)
                for (const std::int32_t h : flat.triangle_hinges[t].edge)
                    if (h >= 0 && hinge_in[static_cast<std::size_t>(h)] == 0) hinge_in[static_cast<std::size_t>(h)] = 2;
    }
    std::vector<std::int32_t> local_hinge(flat.hinges.size(), -1);
    std::vector<std::uint8_t> slot_used(gp.column.size(), 0);
    for (std::size_t h = 0; h < flat.hinges.size(); ++h) {
        if (hinge_in[h] == 0) continue;
        local_hinge[h] = static_cast<std::int32_t>(out.global_hinge.size());
        out.global_hinge.push_back(static_cast<std::uint32_t>(h));
        m.hinges.push_back(to_local(flat.hinges[h], "hinge", h));
        m.hinge_cloth.push_back(flat.hinge_cloth[h]);
        for (int k = 0; k < 16; ++k) slot_used[gp.hinge_slots[16 * h + k]] = 1;
    }
    for (std::size_t t = 0; t < flat.triangles.size(); ++t) {
        if (triangle_in[t] == 0) continue;
        out.global_triangle.push_back(static_cast<std::uint32_t>(t));
        m.triangles.push_back(to_local(flat.triangles[t], "triangle", t));
        m.triangle_rest.push_back(flat.triangle_rest[t]);
        m.triangle_cloth.push_back(flat.triangle_cloth[t]);
        if (per_triangle_bending) {
            TriangleHinges hinges;
            for (int k = 0; k < 3; ++k) {
                const std::int32_t h = flat.triangle_hinges[t].edge[k];
                hinges.edge[k] = h >= 0 ? local_hinge[static_cast<std::size_t>(h)] : -1;
            }
            m.triangle_hinges.push_back(hinges);
            m.shell_rest.push_back(flat.shell_rest[t]);
        }
        for (int k = 0; k < 9; ++k) slot_used[gp.triangle_slots[9 * t + k]] = 1;
    }

    // Pattern rows: an owned row is the global row whole (its slots are all used by the elements
    // touching it); a ghost row keeps the slots the part's elements fill. Columns in the global
    // row's order, so every row sums in the same order as the global one.
    std::vector<std::uint32_t> local_slot(gp.column.size(), kAbsent);
    BlockPattern& lp = m.pattern;
    lp.row_start.assign(1, 0);
    lp.diagonal.assign(n, kAbsent);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t g = out.global_vertex[i];
        for (std::uint32_t s = gp.row_start[g]; s < gp.row_start[g + 1]; ++s) {
            const bool keep = i < out.owned || slot_used[s] != 0;
            if (!keep) continue;
            const std::uint32_t column = local[gp.column[s]];
            if (column == kAbsent)
                throw Error("extract_part: row " + std::to_string(g) + " of part " + std::to_string(p) +
                            " reads vertex " + std::to_string(gp.column[s]) + ", which is not a ghost of it");
            local_slot[s] = static_cast<std::uint32_t>(lp.column.size());
            if (s == gp.diagonal[g]) lp.diagonal[i] = local_slot[s];
            lp.column.push_back(column);
            out.global_slot.push_back(s);
        }
        lp.row_start.push_back(static_cast<std::uint32_t>(lp.column.size()));
        if (lp.diagonal[i] == kAbsent)  // every local vertex lies in an element of the part
            throw Error("extract_part: vertex " + std::to_string(g) + " of part " + std::to_string(p) +
                        " has no diagonal block (internal)");
    }
    lp.triangle_slots.reserve(9 * m.triangles.size());
    for (const std::uint32_t t : out.global_triangle)
        for (int k = 0; k < 9; ++k) lp.triangle_slots.push_back(local_slot[gp.triangle_slots[9 * t + k]]);
    lp.hinge_slots.reserve(16 * m.hinges.size());
    for (const std::uint32_t h : out.global_hinge)
        for (int k = 0; k < 16; ++k) lp.hinge_slots.push_back(local_slot[gp.hinge_slots[16 * h + k]]);

    // Pins of owned vertices only: a ghost's motion arrives from its owner.
    m.vertex_pin.assign(n, -1);
    for (std::size_t k = 0; k < flat.pin_vertex.size(); ++k) {
        const std::uint32_t v = local[flat.pin_vertex[k]];
        if (v == kAbsent || v >= out.owned) continue;
        m.vertex_pin[v] = static_cast<std::int32_t>(m.pin_vertex.size());
        m.pin_vertex.push_back(v);
        m.pin_motion.push_back(flat.pin_motion[k]);
        m.pin_local.push_back(flat.pin_local[k]);
        m.pin_collider.push_back(flat.pin_collider[k]);
        m.pin_collider_vertex.push_back(flat.pin_collider_vertex[k]);
        m.pin_collider_joint.push_back(flat.pin_collider_joint[k]);
    }
    build_gather_tables(m);
    return out;
}

}  // namespace weft
