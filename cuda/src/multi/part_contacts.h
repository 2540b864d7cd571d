#pragma once
/// @file
/// A part's share of the substep's contact list (docs/multi-gpu.md, "Collisions"): the contacts with
/// at least one cloth vertex the part owns. Only those add to the part's rows (their right-hand side
/// and their share of every product), so each part evaluates and multiplies only its share, and a
/// contact across the cut is on both parts. The selection keeps the list's order: every row sums
/// its contacts in the order one GPU does.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>

#include "device_contacts.h"

namespace weft::cuda::multi {

/// One GPU's share of the substep's contacts: its narrow phase's list (device memory every part's
/// GPU can read) and how many it holds.
struct ContactShare {
    const DeviceContact* list = nullptr;
    std::size_t count = 0;
};

/// Scratch bytes `launch_select_part_contacts` needs for a list of `count` contacts.
[[nodiscard]] std::size_t part_contact_selection_bytes(std::size_t count);

/// to[0, *to_count) = the contacts of from[0, count) with a vertex v < `cloth_vertices` and
/// row_of[v] ≠ ~0 (owned here), in list order. `from` may live on another GPU (peer access).
void launch_select_part_contacts(const DeviceContact* from, std::size_t count, const std::uint32_t* row_of,
                                 std::uint32_t cloth_vertices, DeviceContact* to, std::uint32_t* to_count, void* scratch,
                                 std::size_t scratch_bytes, cudaStream_t stream);

/// c.corner_source for the part's first `count` contacts (ContactView::corner_source), from the
/// list's vertices and c.row_of.
void launch_part_corner_sources(const ContactView& c, std::uint32_t count, uint4* corner_source, cudaStream_t stream);

/// counts[v] += the contacts of list[0, count) at cloth vertex v (< cloth_vertices; kinematic
/// vertices are not counted): the contact load of each row, for a re-cut of the parts.
void launch_count_contacts_at_vertices(const DeviceContact* list, std::size_t count, std::uint32_t cloth_vertices,
                                       std::uint32_t* counts, cudaStream_t stream);

}  // namespace weft::cuda::multi
