// Vertex partitions for the multi-GPU solve (weft/backend/vertex_partition.h, docs/multi-gpu.md).
#include "weft/backend/vertex_partition.h"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdio>
#include <limits>

#include "weft/backend/flat_model.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/error.h"

namespace weft {

std::vector<double> row_work(const BlockPattern& pattern) {
    const std::size_t n = pattern.row_start.empty() ? 0 : pattern.row_start.size() - 1;
    std::vector<double> work(n);
    for (std::size_t i = 0; i < n; ++i) work[i] = static_cast<double>(pattern.row_start[i + 1] - pattern.row_start[i]);
    return work;
}

std::vector<double> row_and_contact_work(const BlockPattern& pattern, std::span<const std::uint32_t> contacts_at,
                                         double contact_work) {
    std::vector<double> work = row_work(pattern);
    if (contacts_at.size() != work.size())
        throw Error("row_and_contact_work: " + std::to_string(contacts_at.size()) + " contact counts for " +
                    std::to_string(work.size()) + " rows");
    for (std::size_t i = 0; i < work.size(); ++i) work[i] += contact_work * static_cast<double>(contacts_at[i]);
    return work;
}

double part_work_imbalance(std::span<const double> part_rows, std::span<const std::size_t> part_contacts, double contact_work) {
    if (part_rows.size() != part_contacts.size())
        throw Error("part_work_imbalance: " + std::to_string(part_rows.size()) + " parts' rows but " +
                    std::to_string(part_contacts.size()) + " parts' contacts");
    double total = 0.0, busiest = 0.0;
    for (std::size_t p = 0; p < part_rows.size(); ++p) {
        const double work = part_rows[p] + 4.0 * contact_work * static_cast<double>(part_contacts[p]);
        total += work;
        busiest = std::max(busiest, work);
    }
    return total > 0.0 ? busiest * static_cast<double>(part_rows.size()) / total : 1.0;
}

std::vector<std::uint32_t> cut_order(std::span<const std::uint32_t> order, std::span<const double> work,
                                     std::uint32_t parts, std::uint32_t granule) {
    const std::size_t n = order.size();
    if (work.size() != n)
        throw Error("cut_order: " + std::to_string(work.size()) + " work values for " + std::to_string(n) + " vertices");
    if (granule == 0) throw Error("cut_order: the granule must be at least 1");
    const std::size_t granules = (n + granule - 1) / granule;
    if (parts == 0 || parts > granules)
        throw Error("cut_order: cannot cut " + std::to_string(n) + " vertices (" + std::to_string(granules) +
                    " runs of " + std::to_string(granule) + ") into " + std::to_string(parts) + " parts");
    // prefix[g] = the work of granules [0, g), summed in order (the same bits on every run).
    std::vector<double> prefix(granules + 1, 0.0);
    for (std::size_t g = 0; g < granules; ++g) {
        double sum = 0.0;
        for (std::size_t p = g * granule; p < std::min(n, (g + 1) * granule); ++p) {
            if (order[p] >= n) throw Error("cut_order: order lists vertex " + std::to_string(order[p]) + " of " + std::to_string(n));
            sum += work[order[p]];
        }
        prefix[g + 1] = prefix[g] + sum;
    }
    const double total = prefix[granules];
    // Cut k after the granule boundary nearest to k/parts of the work, keeping every part non-empty.
    std::vector<std::size_t> cut(parts + 1, 0);
    cut[parts] = granules;
    for (std::uint32_t k = 1; k < parts; ++k) {
        const double target = total * static_cast<double>(k) / static_cast<double>(parts);
        auto b = static_cast<std::size_t>(std::lower_bound(prefix.begin(), prefix.end(), target) - prefix.begin());
        if (b > 0 && target - prefix[b - 1] < (b <= granules ? prefix[b] : total) - target) --b;
        const std::size_t lo = cut[k - 1] + 1, hi = granules - (parts - k);
        cut[k] = std::clamp(b, lo, hi);
    }
    std::vector<std::uint32_t> part_of(n, std::numeric_limits<std::uint32_t>::max());
    for (std::uint32_t k = 0; k < parts; ++k)
        for (std::size_t p = cut[k] * granule; p < std::min(n, cut[k + 1] * granule); ++p) {
            if (part_of[order[p]] != std::numeric_limits<std::uint32_t>::max())
                throw Error("cut_order: vertex " + std::to_string(order[p]) + " is listed twice");
            part_of[order[p]] = k;
        }
    return part_of;
}

VertexReach per_triangle_bending_reach(const FlatModel& flat) {
    const std::size_t n = flat.vertex_count, nh = flat.hinges.size();
    // Each hinge's faces, and the hinges through each vertex.
    std::vector<std::array<std::int32_t, 2>> faces(nh, {-1, -1});
    for (std::size_t t = 0; t < flat.triangle_hinges.size(); ++t)
        for (const std::int32_t h : flat.triangle_hinges[t].edge)
            if (h >= 0) {
                auto& f = faces[static_cast<std::size_t>(h)];
                (f[0] < 0 ? f[0] : f[1]) = static_cast<std::int32_t>(t);
            }
    std::vector<std::uint32_t> hinge_start(n + 1, 0), hinge_of;
    for (const Hinge& h : flat.hinges)
        for (const std::uint32_t v : h.v) ++hinge_start[v + 1];
    for (std::size_t i = 0; i < n; ++i) hinge_start[i + 1] += hinge_start[i];
    hinge_of.resize(hinge_start[n]);
    std::vector<std::uint32_t> fill(hinge_start.begin(), hinge_start.end() - 1);
    for (std::size_t h = 0; h < nh; ++h)
        for (const std::uint32_t v : flat.hinges[h].v) hinge_of[fill[v]++] = static_cast<std::uint32_t>(h);
    // Each vertex's list gathered with a stamp per vertex (no repeats), then sorted (a few tens).
    VertexReach out;
    out.start.assign(1, 0);
    std::vector<std::uint32_t> seen(n, std::numeric_limits<std::uint32_t>::max());
    for (std::size_t i = 0; i < n; ++i) {
        const auto first = out.vertex.size();
        const auto stamp = static_cast<std::uint32_t>(i);
        for (std::uint32_t k = hinge_start[i]; k < hinge_start[i + 1]; ++k)
            for (const std::int32_t t : faces[hinge_of[k]]) {
                if (t < 0) continue;
                for (const std::int32_t e : flat.triangle_hinges[static_cast<std::size_t>(t)].edge)
                    if (e >= 0)
                        for (const std::uint32_t v : flat.hinges[static_cast<std::size_t>(e)].v)
                            if (seen[v] != stamp) {
                                seen[v] = stamp;
                                out.vertex.push_back(v);
                            }
            }
        std::sort(out.vertex.begin() + static_cast<std::ptrdiff_t>(first), out.vertex.end());
        out.start.push_back(static_cast<std::uint32_t>(out.vertex.size()));
    }
    return out;
}

VertexPartition build_partition(const BlockPattern& pattern, std::span<const std::uint32_t> part_of,
                                std::uint32_t parts, std::span<const double> work, const VertexReach* reach) {
    const std::size_t n = pattern.row_start.empty() ? 0 : pattern.row_start.size() - 1;
    if (part_of.size() != n || work.size() != n)
        throw Error("build_partition: " + std::to_string(part_of.size()) + " part ids and " + std::to_string(work.size()) +
                    " work values for " + std::to_string(n) + " rows");
    if (reach != nullptr && reach->start.size() != n + 1)
        throw Error("build_partition: a reach over " + std::to_string(reach->start.empty() ? 0 : reach->start.size() - 1) +
                    " vertices for " + std::to_string(n) + " rows");
    if (parts == 0) throw Error("build_partition: 0 parts");
    VertexPartition out;
    out.parts = parts;
    out.part_of.assign(part_of.begin(), part_of.end());
    out.local_index.assign(n, 0);
    out.part.resize(parts);

    // Owned lists: interior rows first, then boundary, each in increasing global id.
    std::vector<std::uint8_t> boundary(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t p = part_of[i];
        if (p >= parts) throw Error("build_partition: vertex " + std::to_string(i) + " is in part " + std::to_string(p) +
                                    " of " + std::to_string(parts));
        for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s) {
            const std::uint32_t j = pattern.column[s];
            if (part_of[j] != p) {
                boundary[i] = 1;
                if (j != i) ++out.quality.cut_blocks;
            }
        }
    }
    for (int pass = 0; pass < 2; ++pass)
        for (std::size_t i = 0; i < n; ++i) {
            if (boundary[i] != static_cast<std::uint8_t>(pass)) continue;
            PartitionPart& part = out.part[part_of[i]];
            out.local_index[i] = static_cast<std::uint32_t>(part.owned.size());
            part.owned.push_back(static_cast<std::uint32_t>(i));
            if (pass == 0) part.interior = static_cast<std::uint32_t>(part.owned.size());
            part.work += work[i];
        }

    // Ghosts: the off-part columns of each part's boundary rows, and the off-part reach of all its
    // rows, by owner part, then global id. The mark array holds the last part that listed each
    // vertex (parts are taken in turn).
    std::vector<std::uint32_t> mark(n, std::numeric_limits<std::uint32_t>::max());
    for (std::uint32_t p = 0; p < parts; ++p) {
        PartitionPart& part = out.part[p];
        const auto add = [&](std::uint32_t j) {
            if (part_of[j] == p || mark[j] == p) return;
            mark[j] = p;
            part.ghosts.push_back(j);
        };
        for (std::size_t k = part.interior; k < part.owned.size(); ++k) {
            const std::uint32_t i = part.owned[k];
            for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s) add(pattern.column[s]);
        }
        if (reach != nullptr)
            for (const std::uint32_t i : part.owned)
                for (std::uint32_t s = reach->start[i]; s < reach->start[i + 1]; ++s) {
                    if (reach->vertex[s] >= n)
                        throw Error("build_partition: vertex " + std::to_string(i) + " reaches vertex " +
                                    std::to_string(reach->vertex[s]) + " of " + std::to_string(n));
                    add(reach->vertex[s]);
                }
        std::sort(part.ghosts.begin(), part.ghosts.end(), [&](std::uint32_t a, std::uint32_t b) {
            return part_of[a] != part_of[b] ? part_of[a] < part_of[b] : a < b;
        });
        part.ghost_start.assign(parts + 1, 0);
        for (const std::uint32_t g : part.ghosts) ++part.ghost_start[part_of[g] + 1];
        for (std::uint32_t q = 0; q < parts; ++q) part.ghost_start[q + 1] += part.ghost_start[q];
        out.quality.halo_vertices += part.ghosts.size();
        out.quality.boundary_vertices += part.boundary();
    }

    // Sends mirror the ghosts: part p sends to q what q lists as its ghosts from p, in q's order.
    for (std::uint32_t p = 0; p < parts; ++p) {
        PartitionPart& part = out.part[p];
        part.send_start.assign(parts + 1, 0);
        for (std::uint32_t q = 0; q < parts; ++q) {
            const PartitionPart& receiver = out.part[q];
            for (std::uint32_t k = receiver.ghost_start[p]; k < receiver.ghost_start[p + 1]; ++k)
                part.send.push_back(out.local_index[receiver.ghosts[k]]);
            part.send_start[q + 1] = static_cast<std::uint32_t>(part.send.size());
        }
    }

    double total = 0.0, largest = 0.0;
    for (const PartitionPart& part : out.part) {
        total += part.work;
        largest = std::max(largest, part.work);
    }
    out.quality.imbalance = total > 0.0 ? largest * static_cast<double>(parts) / total : 1.0;
    return out;
}

std::string describe(const PartitionQuality& quality, std::uint32_t parts) {
    char line[200];
    std::snprintf(line, sizeof line, "%u parts: %llu cut blocks, %llu halo vertices, %llu boundary vertices, imbalance %.3f",
                  parts, static_cast<unsigned long long>(quality.cut_blocks),
                  static_cast<unsigned long long>(quality.halo_vertices),
                  static_cast<unsigned long long>(quality.boundary_vertices), quality.imbalance);
    return line;
}

VertexPartition partition_along_preconditioner(const FlatModel& flat, std::uint32_t parts) {
    const SchwarzHierarchy h = build_schwarz_hierarchy(flat.initial_positions, flat.pattern);
    const std::vector<double> work = row_work(flat.pattern);
    return build_partition(flat.pattern, cut_order(h.order, work, parts, SchwarzHierarchy::kDomainSize), parts, work);
}

}  // namespace weft
