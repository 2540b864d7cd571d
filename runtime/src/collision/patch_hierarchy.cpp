// Patch hierarchy build: connected median splits and bottom-up contours (patch_hierarchy.h).
#include "weft/backend/patch_hierarchy.h"

#include <algorithm>
#include <string>

#include "weft/error.h"

namespace weft::collision {
namespace {

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
    return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
}

/// A contour edge with its undirected key, the sort order of a node's contour during the build.
struct KeyedEdge {
    std::uint64_t key;
    std::uint32_t a, b;
};

/// Symmetric difference of two key-sorted contours: edges in both children are interior to the
/// parent. Clears `consistent` when such an edge is traversed in the same direction on both sides
/// (the triangles around it are not consistently oriented).
void merge_contours(const std::vector<KeyedEdge>& l, const std::vector<KeyedEdge>& r, std::vector<KeyedEdge>& out,
                    bool& consistent) {
    out.clear();
    out.reserve(l.size() + r.size());
    std::size_t i = 0, j = 0;
    while (i < l.size() || j < r.size()) {
        if (j == r.size() || (i < l.size() && l[i].key < r[j].key)) {
            out.push_back(l[i++]);
        } else if (i == l.size() || r[j].key < l[i].key) {
            out.push_back(r[j++]);
        } else {
            if (l[i].a != r[j].b) consistent = false;
            ++i;
            ++j;
        }
    }
}

/// Sorted distinct vertices of a contour.
void contour_vertices(const std::vector<KeyedEdge>& c, std::vector<std::uint32_t>& out) {
    out.clear();
    for (const KeyedEdge& e : c) {
        out.push_back(e.a);
        out.push_back(e.b);
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
}

}  // namespace

PatchHierarchy build_patch_hierarchy(std::span<const Vec3d> rest, std::span<const Triangle> triangles,
                                     std::span<const Edge> edges, std::span<const std::uint32_t> triangle_cloth) {
    const std::size_t n = rest.size(), nt = triangles.size();
    if (nt >= kNone / 2) throw Error("patch hierarchy: too many triangles (" + std::to_string(nt) + ")");
    if (n >= kNone) throw Error("patch hierarchy: too many vertices (" + std::to_string(n) + ")");
    if (!triangle_cloth.empty() && triangle_cloth.size() != nt)
        throw Error("patch hierarchy: " + std::to_string(triangle_cloth.size()) + " triangle cloth ids for " +
                    std::to_string(nt) + " triangles");
    for (std::size_t t = 0; t < nt; ++t) {
        const Triangle& tri = triangles[t];
        for (std::uint32_t v : tri.v)
            if (v >= n)
                throw Error("patch hierarchy: triangle " + std::to_string(t) + " uses vertex " + std::to_string(v));
        if (tri.v[0] == tri.v[1] || tri.v[1] == tri.v[2] || tri.v[0] == tri.v[2])
            throw Error("patch hierarchy: triangle " + std::to_string(t) + " repeats a vertex");
    }
    for (std::size_t e = 0; e < edges.size(); ++e)
        for (std::uint32_t v : edges[e].v)
            if (v >= n) throw Error("patch hierarchy: edge " + std::to_string(e) + " uses vertex " + std::to_string(v));
    const auto cloth = [&](std::size_t t) { return triangle_cloth.empty() ? 0U : triangle_cloth[t]; };

    PatchHierarchy h;
    h.vertex_count = static_cast<std::uint32_t>(n);
    h.triangle_count = static_cast<std::uint32_t>(nt);
    h.edge_count = static_cast<std::uint32_t>(edges.size());
    h.triangles.assign(triangles.begin(), triangles.end());

    // ---- Edge incidence: adjacency, and the triangles the disk test must refuse ----------------
    // A triangle is "bad" (any node holding it is not a disk) when one of its edges has more than
    // two triangles or two triangles of different cloths, when a neighbour across an edge runs the
    // edge in the same direction (inconsistent orientation), or when one of its vertices is not
    // manifold (its triangles form more than one fan).
    std::vector<std::uint8_t> bad(nt, 0);
    struct Incidence {
        std::uint64_t key;
        std::uint32_t tri;
        std::uint32_t from;  // the triangle runs the edge from this vertex
    };
    std::vector<Incidence> inc;
    inc.reserve(3 * nt);
    for (std::uint32_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = triangles[t].v[k], b = triangles[t].v[(k + 1) % 3];
            inc.push_back({edge_key(a, b), t, a});
        }
    std::sort(inc.begin(), inc.end(),
              [](const Incidence& p, const Incidence& q) { return p.key != q.key ? p.key < q.key : p.tri < q.tri; });
    std::vector<std::uint32_t> adj_count(nt + 1, 0);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> links;  // (t, neighbour), both directions
    for (std::size_t i = 0; i < inc.size();) {
        std::size_t j = i;
        while (j < inc.size() && inc[j].key == inc[i].key) ++j;
        const std::size_t g = j - i;
        bool flag = g > 2;
        if (g == 2) flag = inc[i].from == inc[i + 1].from || cloth(inc[i].tri) != cloth(inc[i + 1].tri);
        for (std::size_t p = i; p < j; ++p) {
            if (flag) bad[inc[p].tri] = 1;
            for (std::size_t q = i; q < j; ++q)
                if (p != q && cloth(inc[p].tri) == cloth(inc[q].tri) && inc[p].tri != inc[q].tri)
                    links.push_back({inc[p].tri, inc[q].tri});
        }
        i = j;
    }
    std::sort(links.begin(), links.end());
    links.erase(std::unique(links.begin(), links.end()), links.end());
    for (const auto& [t, u] : links) ++adj_count[t + 1];
    for (std::size_t t = 0; t < nt; ++t) adj_count[t + 1] += adj_count[t];
    std::vector<std::uint32_t> adj(links.size());
    for (std::size_t i = 0; i < links.size(); ++i) adj[i] = links[i].second;  // links sorted by t: CSR order
    const auto neighbours = [&](std::uint32_t t) {
        return std::span<const std::uint32_t>(adj.data() + adj_count[t], adj.data() + adj_count[t + 1]);
    };

    // Vertex fans. Triangles around v are linked when they share an edge at v (a second vertex);
    // more than one linked group is a non-manifold vertex.
    std::vector<std::uint32_t> vt_first(n + 1, 0), vt(3 * nt);
    for (const Triangle& tri : triangles)
        for (std::uint32_t v : tri.v) ++vt_first[v + 1];
    for (std::size_t v = 0; v < n; ++v) vt_first[v + 1] += vt_first[v];
    {
        std::vector<std::uint32_t> at(vt_first.begin(), vt_first.end() - 1);
        for (std::uint32_t t = 0; t < nt; ++t)
            for (std::uint32_t v : triangles[t].v) vt[at[v]++] = t;  // ascending t per vertex
    }
    std::vector<std::uint32_t> group;
    for (std::uint32_t v = 0; v < n; ++v) {
        const std::uint32_t b = vt_first[v], e = vt_first[v + 1];
        if (e - b < 2) continue;
        group.assign(e - b, 0);
        for (std::uint32_t i = 0; i < e - b; ++i) group[i] = i;
        const auto find = [&](std::uint32_t i) {
            while (group[i] != i) i = group[i] = group[group[i]];
            return i;
        };
        for (std::uint32_t i = b; i < e; ++i)
            for (std::uint32_t j = i + 1; j < e; ++j) {
                const Triangle &p = triangles[vt[i]], &q = triangles[vt[j]];
                int shared = 0;
                for (std::uint32_t x : p.v)
                    for (std::uint32_t y : q.v) shared += x == y ? 1 : 0;
                if (shared >= 2) group[find(i - b)] = find(j - b);
            }
        int roots = 0;
        for (std::uint32_t i = 0; i < e - b; ++i) roots += find(i) == i ? 1 : 0;
        if (roots > 1)
            for (std::uint32_t i = b; i < e; ++i) bad[vt[i]] = 1;
    }

    // ---- Splits --------------------------------------------------------------------------------
    std::vector<Vec3d> centroid(nt);
    for (std::size_t t = 0; t < nt; ++t) {
        const Triangle& tri = triangles[t];
        centroid[t] = (rest[tri.v[0]] + rest[tri.v[1]] + rest[tri.v[2]]) / 3.0;
    }
    // side[t]: a label per triangle; fresh labels mark subsets and components without clearing.
    std::vector<std::uint32_t> side(nt, 0);
    std::uint32_t next_label = 1;
    std::vector<std::uint32_t> queue;
    struct Component {
        std::uint32_t label, size, min_tri;
    };
    std::vector<Component> comps;
    // Relabels each connected component of the triangles of `order[f, f + c)` labelled `label`.
    const auto components = [&](std::span<const std::uint32_t> range, std::uint32_t label) {
        comps.clear();
        for (std::uint32_t s : range) {
            if (side[s] != label) continue;
            const std::uint32_t mine = next_label++;
            Component comp{mine, 0, s};
            queue.assign(1, s);
            side[s] = mine;
            for (std::size_t q = 0; q < queue.size(); ++q) {
                const std::uint32_t t = queue[q];
                ++comp.size;
                comp.min_tri = std::min(comp.min_tri, t);
                for (std::uint32_t u : neighbours(t))
                    if (side[u] == label) {
                        side[u] = mine;
                        queue.push_back(u);
                    }
            }
            comps.push_back(comp);
        }
        // The largest component; ties to the one holding the lowest triangle (order independent).
        return *std::min_element(comps.begin(), comps.end(), [](const Component& p, const Component& q) {
            return p.size != q.size ? p.size > q.size : p.min_tri < q.min_tri;
        });
    };

    std::vector<std::uint32_t> order(nt);
    for (std::uint32_t t = 0; t < nt; ++t) order[t] = t;
    // Roots: connected components, in order of their lowest triangle.
    {
        const std::uint32_t all = next_label++;
        std::fill(side.begin(), side.end(), all);
        std::vector<std::uint32_t> sorted;
        sorted.reserve(nt);
        for (std::uint32_t s = 0; s < nt; ++s) {
            if (side[s] != all) continue;
            (void)components(std::span<const std::uint32_t>(&s, 1), all);
            const std::uint32_t first = static_cast<std::uint32_t>(sorted.size());
            sorted.insert(sorted.end(), queue.begin(), queue.end());
            h.node_first.push_back(first);
            h.node_count.push_back(static_cast<std::uint32_t>(queue.size()));
            h.node_parent.push_back(kNone);
        }
        order = std::move(sorted);
    }
    std::vector<std::uint32_t> level;
    level.assign(h.node_first.size(), 0);
    std::vector<std::uint32_t> scratch;
    for (std::uint32_t node = 0; node < h.node_first.size(); ++node) {
        const std::uint32_t f = h.node_first[node], c = h.node_count[node];
        if (c == 1) {
            h.node_child.push_back(kNone);
            continue;
        }
        const std::span<std::uint32_t> range(order.data() + f, c);
        // Median split along the longest extent of the centroids; the order (coordinate, index) is
        // total, so the halves as sets do not depend on how nth_element arranges them.
        Vec3d lo = centroid[range[0]], hi = lo;
        for (std::uint32_t t : range)
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min(lo[k], centroid[t][k]);
                hi[k] = std::max(hi[k], centroid[t][k]);
            }
        const Vec3d ext = hi - lo;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        const auto mid = range.begin() + c / 2;
        std::nth_element(range.begin(), mid, range.end(), [&](std::uint32_t p, std::uint32_t q) {
            const double a = centroid[p][axis], b = centroid[q][axis];
            return a != b ? a < b : p < q;
        });
        // Connectivity repair (patch_hierarchy.h).
        const std::uint32_t la = next_label++, lb = next_label++;
        for (auto it = range.begin(); it != range.end(); ++it) side[*it] = it < mid ? la : lb;
        const Component keep_a = components(range, la);
        const std::uint32_t la2 = next_label++, lb2 = next_label++;
        for (std::uint32_t t : range) side[t] = side[t] == keep_a.label ? la2 : lb2;
        const Component keep_b = components(range, lb2);
        scratch.clear();
        for (std::uint32_t t : range)
            if (side[t] != keep_b.label) scratch.push_back(t);
        const auto first_size = static_cast<std::uint32_t>(scratch.size());
        for (std::uint32_t t : range)
            if (side[t] == keep_b.label) scratch.push_back(t);
        std::copy(scratch.begin(), scratch.end(), range.begin());
        const auto child = static_cast<std::uint32_t>(h.node_first.size());
        h.node_child.push_back(child);
        h.node_first.push_back(f);
        h.node_count.push_back(first_size);
        h.node_first.push_back(f + first_size);
        h.node_count.push_back(c - first_size);
        h.node_parent.push_back(node);
        h.node_parent.push_back(node);
        level.push_back(level[node] + 1);
        level.push_back(level[node] + 1);
    }
    const std::size_t nodes = h.node_first.size();
    h.triangle_order = std::move(order);
    h.triangle_leaf.assign(nt, kNone);
    for (std::uint32_t node = 0; node < nodes; ++node)
        if (h.node_child[node] == kNone) h.triangle_leaf[h.triangle_order[h.node_first[node]]] = node;
    // Breadth-first numbering: levels are non-decreasing in the node id.
    for (std::uint32_t node = 0; node < nodes; ++node)
        if (node == 0 || level[node] != level[node - 1]) h.level_first.push_back(node);
    h.level_first.push_back(static_cast<std::uint32_t>(nodes));

    // ---- Contours and the disk test, bottom-up ---------------------------------------------------
    h.node_flags.assign(nodes, 0);
    std::vector<std::vector<KeyedEdge>> contour(nodes);
    std::vector<std::uint32_t> vertex_count(nodes, 0);
    std::vector<std::uint8_t> node_bad(nodes, 0);
    std::vector<std::uint32_t> vl, vr;
    for (std::size_t i = nodes; i-- > 0;) {
        const auto node = static_cast<std::uint32_t>(i);
        std::vector<KeyedEdge>& mine = contour[node];
        if (h.node_child[node] == kNone) {
            const std::uint32_t t = h.triangle_order[h.node_first[node]];
            const Triangle& tri = triangles[t];
            for (int k = 0; k < 3; ++k)
                mine.push_back({edge_key(tri.v[k], tri.v[(k + 1) % 3]), tri.v[k], tri.v[(k + 1) % 3]});
            std::sort(mine.begin(), mine.end(), [](const KeyedEdge& p, const KeyedEdge& q) { return p.key < q.key; });
            vertex_count[node] = 3;
            node_bad[node] = bad[t];
            h.node_flags[node] = PatchHierarchy::kDisk;
            continue;
        }
        const std::uint32_t l = h.node_child[node], r = l + 1;
        bool consistent = true;
        merge_contours(contour[l], contour[r], mine, consistent);
        contour_vertices(contour[l], vl);
        contour_vertices(contour[r], vr);
        // A vertex of both children has triangles on both sides, so it is on both contours.
        std::size_t shared = 0;
        for (std::size_t a = 0, b = 0; a < vl.size() && b < vr.size();) {
            if (vl[a] < vr[b]) {
                ++a;
            } else if (vr[b] < vl[a]) {
                ++b;
            } else {
                ++shared;
                ++a;
                ++b;
            }
        }
        vertex_count[node] = static_cast<std::uint32_t>(vertex_count[l] + vertex_count[r] - shared);
        node_bad[node] = static_cast<std::uint8_t>(node_bad[l] | node_bad[r] | (consistent ? 0 : 1));
        if (node_bad[node] != 0 || mine.empty()) continue;
        // Every contour vertex on exactly two contour edges: one fan per vertex within the node.
        vl.clear();
        for (const KeyedEdge& e : mine) {
            vl.push_back(e.a);
            vl.push_back(e.b);
        }
        std::sort(vl.begin(), vl.end());
        bool two_each = true;
        for (std::size_t a = 0; a < vl.size() && two_each; a += 2) {
            const bool pair = a + 1 < vl.size() && vl[a] == vl[a + 1];
            const bool only_two = a + 2 >= vl.size() || vl[a + 2] != vl[a];
            two_each = pair && only_two;
        }
        // χ = V − E + F with E = (3F + B)/2 (interior edges have two triangles, contour edges one).
        const std::int64_t faces = h.node_count[node], boundary = static_cast<std::int64_t>(mine.size());
        const std::int64_t twice_chi = 2 * std::int64_t{vertex_count[node]} - (3 * faces + boundary) + 2 * faces;
        if (two_each && twice_chi == 2) h.node_flags[node] = PatchHierarchy::kDisk;
    }
    // Flat contours of the testable nodes.
    h.contour_first.assign(nodes + 1, 0);
    for (std::size_t node = 0; node < nodes; ++node) {
        const bool stored = h.node_child[node] != kNone && (h.node_flags[node] & PatchHierarchy::kDisk) != 0;
        h.contour_first[node + 1] =
            h.contour_first[node] + (stored ? static_cast<std::uint32_t>(contour[node].size()) : 0U);
    }
    h.contour_edges.resize(h.contour_first[nodes]);
    for (std::size_t node = 0; node < nodes; ++node) {
        if (h.contour_first[node + 1] == h.contour_first[node]) continue;
        std::uint32_t at = h.contour_first[node];
        for (const KeyedEdge& e : contour[node]) h.contour_edges[at++] = {e.a, e.b};
    }

    // ---- Reference triangles of vertices and edges -------------------------------------------------
    h.vertex_triangle.assign(n, kNone);
    for (std::size_t v = 0; v < n; ++v)
        if (vt_first[v + 1] > vt_first[v]) h.vertex_triangle[v] = vt[vt_first[v]];  // lowest index
    if (!edges.empty()) {
        h.edge_triangle.assign(edges.size(), kNone);
        // inc is sorted by (key, triangle): the first incidence of a key is its lowest triangle.
        for (std::size_t e = 0; e < edges.size(); ++e) {
            const std::uint64_t key = edge_key(edges[e].v[0], edges[e].v[1]);
            const auto it = std::lower_bound(inc.begin(), inc.end(), key,
                                             [](const Incidence& p, std::uint64_t k) { return p.key < k; });
            if (it != inc.end() && it->key == key) h.edge_triangle[e] = it->tri;
        }
    }
    return h;
}

}  // namespace weft::collision
