// Cooking: turns a triangle mesh into a Fabric (rest data, hinges, masses, BSR pattern).
#include "weft/fabric.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "weft/error.h"
#include "weft/parameters.h"
#include "weft/physics/bending.h"
#include "weft/physics/membrane.h"

namespace weft {
namespace {

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
    if (a > b) std::swap(a, b);
    return (std::uint64_t{a} << 32) | b;
}

void validate_input(const MeshData& mesh) {
    const std::string& src = mesh.source.empty() ? std::string("mesh") : mesh.source;
    if (mesh.positions.empty() || mesh.triangles.empty())
        throw Error(src + ": mesh has no triangles (" + std::to_string(mesh.positions.size()) + " vertices, " +
                    std::to_string(mesh.triangles.size()) + " triangles)");
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
        if (!physics::is_finite(mesh.positions[i]))
            throw Error(src + ": vertex " + std::to_string(i) + " has a non-finite position");
    const auto n = mesh.positions.size();
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (std::uint32_t v : mesh.triangles[t].v)
            if (v >= n)
                throw Error(src + ": triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                            " but the mesh has only " + std::to_string(n) + " vertices");
}

}  // namespace

std::shared_ptr<const Fabric> Fabric::cook(const MeshData& mesh, const FabricDesc& desc) {
    validate_input(mesh);
    const std::string src = mesh.source.empty() ? std::string("mesh") : mesh.source;
    const ParameterRange& density = parameter("cloth", "density").range;
    if (!density.contains(desc.density))
        throw Error(src + ": density " + std::to_string(desc.density) + " kg/m² is outside " + density.text());

    std::shared_ptr<Fabric> fabric(new Fabric());
    Fabric& f = *fabric;
    f.desc_ = desc;
    CookReport& report = f.report_;
    report.welded_vertices = mesh.welded_vertices;

    // 1. Drop degenerate and duplicate triangles. A triangle is degenerate when its area is tiny
    //    against its longest edge (a sliver of zero height): it has no rest frame for the membrane.
    std::vector<Triangle> tris;
    tris.reserve(mesh.triangles.size());
    std::unordered_map<std::uint64_t, std::vector<std::size_t>> seen;  // hash of sorted triple → kept tris
    for (const Triangle& t : mesh.triangles) {
        const Vec3d a = mesh.positions[t.v[0]], b = mesh.positions[t.v[1]], c = mesh.positions[t.v[2]];
        const double area2 = physics::length(physics::cross(b - a, c - a));
        const double longest = std::max({physics::length_squared(b - a), physics::length_squared(c - b),
                                         physics::length_squared(a - c)});
        if (t.v[0] == t.v[1] || t.v[1] == t.v[2] || t.v[0] == t.v[2] || !(area2 > 1e-10 * longest) ||
            longest == 0.0) {
            ++report.degenerate_triangles;
            continue;
        }
        std::uint32_t s[3] = {t.v[0], t.v[1], t.v[2]};
        std::sort(s, s + 3);
        const std::uint64_t h = (std::uint64_t{s[0]} * 0x9E3779B97F4A7C15ULL) ^ (std::uint64_t{s[1]} << 21) ^ s[2];
        bool duplicate = false;
        for (std::size_t k : seen[h]) {
            std::uint32_t o[3] = {tris[k].v[0], tris[k].v[1], tris[k].v[2]};
            std::sort(o, o + 3);
            if (o[0] == s[0] && o[1] == s[1] && o[2] == s[2]) duplicate = true;
        }
        if (duplicate) {
            ++report.duplicate_triangles;
            continue;
        }
        seen[h].push_back(tris.size());
        tris.push_back(t);
    }
    if (tris.empty())
        throw Error(src + ": every triangle is degenerate (zero area) — nothing to simulate");
    if (report.degenerate_triangles > 0)
        report.warnings.push_back(std::to_string(report.degenerate_triangles) + " degenerate (zero-area) triangles dropped");
    if (report.duplicate_triangles > 0)
        report.warnings.push_back(std::to_string(report.duplicate_triangles) + " duplicate triangles dropped");

    // 2. Compact: keep only referenced vertices, in their original order.
    std::vector<std::uint32_t> remap(mesh.positions.size(), ~0U);
    for (const Triangle& t : tris)
        for (std::uint32_t v : t.v) remap[v] = 0;
    std::uint32_t next = 0;
    for (std::size_t i = 0; i < remap.size(); ++i) {
        if (remap[i] == 0) {
            remap[i] = next++;
            f.rest_positions_.push_back(mesh.positions[i]);
        } else {
            ++report.unreferenced_vertices;
        }
    }
    if (report.unreferenced_vertices > 0)
        report.warnings.push_back(std::to_string(report.unreferenced_vertices) + " unreferenced vertices removed");
    for (Triangle& t : tris)
        for (std::uint32_t& v : t.v) v = remap[v];
    f.triangles_ = std::move(tris);
    const std::size_t nv = f.rest_positions_.size();
    const std::size_t nt = f.triangles_.size();

    // 3. Per-triangle membrane rest data and lumped masses (a third of each triangle's mass per corner).
    f.triangle_rest_.resize(nt);
    f.masses_.assign(nv, 0.0);
    double edge_sum = 0.0;
    for (std::size_t t = 0; t < nt; ++t) {
        const auto& v = f.triangles_[t].v;
        const Vec3d a = f.rest_positions_[v[0]], b = f.rest_positions_[v[1]], c = f.rest_positions_[v[2]];
        TriangleRest& r = f.triangle_rest_[t];
        physics::membrane_rest(a, b, c, r.dm_inv, r.area);
        f.total_area_ += r.area;
        for (std::uint32_t k : v) f.masses_[k] += desc.density * r.area / 3.0;
        edge_sum += physics::length(b - a) + physics::length(c - b) + physics::length(a - c);
    }
    f.mean_edge_length_ = edge_sum / (3.0 * static_cast<double>(nt));

    // 4. Hinges over interior manifold edges. Each triangle contributes its three directed edges;
    //    an edge with two triangles becomes a hinge, one with more is non-manifold (no hinge, reported).
    struct EdgeUse { std::uint32_t tri; std::uint32_t from, to, opposite; int corner; };
    std::unordered_map<std::uint64_t, std::vector<EdgeUse>> edges;
    edges.reserve(nt * 2);
    for (std::uint32_t t = 0; t < nt; ++t) {
        const auto& v = f.triangles_[t].v;
        for (int k = 0; k < 3; ++k)
            edges[edge_key(v[k], v[(k + 1) % 3])].push_back({t, v[k], v[(k + 1) % 3], v[(k + 2) % 3], k});
    }
    // Deterministic order: sort the interior edges by key.
    std::vector<std::uint64_t> keys;
    keys.reserve(edges.size());
    for (const auto& [key, uses] : edges) keys.push_back(key);
    std::sort(keys.begin(), keys.end());
    std::size_t flipped = 0;
    f.triangle_hinges_.assign(nt, TriangleHinges{});
    for (std::uint64_t key : keys) {
        const auto& uses = edges[key];
        if (uses.size() > 2) {
            ++report.non_manifold_edges;
            continue;
        }
        if (uses.size() != 2) continue;
        Hinge h;
        h.v[0] = uses[0].from;
        h.v[1] = uses[0].to;
        h.v[2] = uses[0].opposite;
        h.v[3] = uses[1].opposite;
        if (uses[1].from == uses[0].from) ++flipped;  // neighbours wound inconsistently
        Vec3d x[4];
        for (int k = 0; k < 4; ++k) x[k] = f.rest_positions_[h.v[k]];
        h.weight = physics::hinge_weight(x);
        h.rest_angle = desc.flat_rest_bending ? 0.0 : physics::dihedral_angle(x);
        if (!std::isfinite(h.weight) || !std::isfinite(h.rest_angle)) continue;
        for (const EdgeUse& use : uses) f.triangle_hinges_[use.tri].edge[use.corner] = static_cast<std::int32_t>(f.hinges_.size());
        f.hinges_.push_back(h);
    }
    if (report.non_manifold_edges > 0)
        report.warnings.push_back(std::to_string(report.non_manifold_edges) +
                                  " non-manifold edges (shared by more than two triangles): no bending across them");
    if (flipped > 0)
        report.warnings.push_back(std::to_string(flipped) + " edges join inconsistently wound triangles");

    // 5. Block pattern: vertex i couples to j when they share a triangle or a hinge.
    std::vector<std::vector<std::uint32_t>> adjacency(nv);
    for (std::uint32_t i = 0; i < nv; ++i) adjacency[i].push_back(i);
    for (const Triangle& t : f.triangles_)
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                if (a != b) adjacency[t.v[a]].push_back(t.v[b]);
    for (const Hinge& h : f.hinges_) {
        adjacency[h.v[2]].push_back(h.v[3]);
        adjacency[h.v[3]].push_back(h.v[2]);
    }
    BlockPattern& p = f.pattern_;
    p.row_start.resize(nv + 1);
    p.diagonal.resize(nv);
    p.row_start[0] = 0;
    for (std::uint32_t i = 0; i < nv; ++i) {
        auto& row = adjacency[i];
        std::sort(row.begin(), row.end());
        row.erase(std::unique(row.begin(), row.end()), row.end());
        p.row_start[i + 1] = p.row_start[i] + static_cast<std::uint32_t>(row.size());
        for (std::uint32_t j : row) {
            if (j == i) p.diagonal[i] = static_cast<std::uint32_t>(p.column.size());
            p.column.push_back(j);
        }
    }
    const auto slot = [&p](std::uint32_t i, std::uint32_t j) {
        const auto first = p.column.begin() + p.row_start[i];
        const auto last = p.column.begin() + p.row_start[i + 1];
        return static_cast<std::uint32_t>(std::lower_bound(first, last, j) - p.column.begin());
    };
    p.triangle_slots.resize(nt * 9);
    for (std::size_t t = 0; t < nt; ++t)
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                p.triangle_slots[t * 9 + static_cast<std::size_t>(a * 3 + b)] =
                    slot(f.triangles_[t].v[a], f.triangles_[t].v[b]);
    p.hinge_slots.resize(f.hinges_.size() * 16);
    for (std::size_t k = 0; k < f.hinges_.size(); ++k)
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
                p.hinge_slots[k * 16 + static_cast<std::size_t>(a * 4 + b)] = slot(f.hinges_[k].v[a], f.hinges_[k].v[b]);
    return fabric;
}

std::size_t Fabric::memory_bytes() const {
    return rest_positions_.capacity() * sizeof(Vec3d) + triangles_.capacity() * sizeof(Triangle) +
           triangle_rest_.capacity() * sizeof(TriangleRest) + hinges_.capacity() * sizeof(Hinge) +
           triangle_hinges_.capacity() * sizeof(TriangleHinges) + masses_.capacity() * sizeof(double) +
           (pattern_.row_start.capacity() + pattern_.column.capacity() + pattern_.diagonal.capacity() +
            pattern_.triangle_slots.capacity() + pattern_.hinge_slots.capacity()) *
               sizeof(std::uint32_t);
}

}  // namespace weft
