// Flattening of the model into one global system (see weft/backend/flat_model.h).
#include "weft/backend/flat_model.h"

#include <string>
#include <vector>

#include "weft/collider.h"
#include "weft/error.h"

namespace weft {

void build_gather_tables(FlatModel& f) {
    // Counting sort by destination: entries stay in element order (deterministic).
    const auto build_gather = [](std::size_t rows, const std::vector<std::uint32_t>& dest,
                                 std::vector<std::uint32_t>& start, std::vector<std::uint32_t>& index) {
        start.assign(rows + 1, 0);
        for (std::uint32_t d : dest) ++start[d + 1];
        for (std::size_t r = 0; r < rows; ++r) start[r + 1] += start[r];
        index.resize(dest.size());
        std::vector<std::uint32_t> cursor(start.begin(), start.end() - 1);
        for (std::size_t e = 0; e < dest.size(); ++e) index[cursor[dest[e]]++] = static_cast<std::uint32_t>(e);
    };
    const BlockPattern& p = f.pattern;
    std::vector<std::uint32_t> dest;
    dest.reserve(3 * f.triangles.size() + 4 * f.hinges.size());
    for (const Triangle& t : f.triangles)
        for (std::uint32_t v : t.v) dest.push_back(v);
    for (const Hinge& h : f.hinges)
        for (std::uint32_t v : h.v) dest.push_back(v);
    build_gather(f.vertex_count, dest, f.vertex_force_start, f.vertex_force_index);
    dest.clear();
    dest.reserve(p.triangle_slots.size() + p.hinge_slots.size());
    dest.insert(dest.end(), p.triangle_slots.begin(), p.triangle_slots.end());
    dest.insert(dest.end(), p.hinge_slots.begin(), p.hinge_slots.end());
    build_gather(p.column.size(), dest, f.slot_block_start, f.slot_block_index);
}

FlatModel flatten(const Model& model) {
    FlatModel f;
    const std::size_t cloths = model.cloths.size();
    f.cloth_vertex_offset.assign(cloths + 1, 0);
    f.cloth_triangle_offset.assign(cloths + 1, 0);
    f.cloth_hinge_offset.assign(cloths + 1, 0);
    std::size_t blocks = 0;
    // Pins that follow a character: its pose at t = 0, placed once per collider (not once per pin).
    std::vector<std::vector<Vec3d>> start_positions(model.colliders.size());
    std::vector<std::vector<Affine>> start_maps(model.colliders.size());
    for (std::size_t c = 0; c < cloths; ++c) {
        const auto& fabric = model.cloths[c].fabric;
        if (!fabric) throw Error("cloth '" + model.cloths[c].name + "' has no fabric");
        f.cloth_vertex_offset[c + 1] = f.cloth_vertex_offset[c] + static_cast<std::uint32_t>(fabric->vertex_count());
        f.cloth_triangle_offset[c + 1] = f.cloth_triangle_offset[c] + static_cast<std::uint32_t>(fabric->triangle_count());
        f.cloth_hinge_offset[c + 1] = f.cloth_hinge_offset[c] + static_cast<std::uint32_t>(fabric->hinges().size());
        blocks += fabric->pattern().block_count();
    }
    const std::size_t nv = f.cloth_vertex_offset[cloths];
    const std::size_t nt = f.cloth_triangle_offset[cloths];
    const std::size_t nh = f.cloth_hinge_offset[cloths];
    f.vertex_count = nv;
    f.initial_positions.reserve(nv);
    f.initial_velocities.reserve(nv);
    f.mass.reserve(nv);
    f.vertex_cloth.reserve(nv);
    f.triangles.reserve(nt);
    f.triangle_rest.reserve(nt);
    f.triangle_cloth.reserve(nt);
    f.hinges.reserve(nh);
    f.hinge_cloth.reserve(nh);
    f.triangle_hinges.reserve(nt);
    f.shell_rest.reserve(nt);
    BlockPattern& p = f.pattern;
    p.row_start.reserve(nv + 1);
    p.row_start.push_back(0);
    p.column.reserve(blocks);
    p.diagonal.reserve(nv);
    p.triangle_slots.reserve(nt * 9);
    p.hinge_slots.reserve(nh * 16);
    f.vertex_pin.assign(nv, -1);

    for (std::size_t c = 0; c < cloths; ++c) {
        const ClothDesc& cloth = model.cloths[c];
        const Fabric& fab = *cloth.fabric;
        const std::uint32_t vo = f.cloth_vertex_offset[c];
        const auto slot_offset = static_cast<std::uint32_t>(p.column.size());
        for (std::size_t i = 0; i < fab.vertex_count(); ++i) {
            f.initial_positions.push_back(cloth.transform.apply(fab.rest_positions()[i]));
            f.initial_velocities.push_back(cloth.initial_velocity);
            f.mass.push_back(fab.masses()[i]);
            f.vertex_cloth.push_back(static_cast<std::uint32_t>(c));
        }
        for (std::size_t t = 0; t < fab.triangle_count(); ++t) {
            Triangle tri = fab.triangles()[t];
            for (auto& v : tri.v) v += vo;
            f.triangles.push_back(tri);
            f.triangle_rest.push_back(fab.triangle_rest()[t]);
            f.triangle_cloth.push_back(static_cast<std::uint32_t>(c));
        }
        const std::int32_t ho = static_cast<std::int32_t>(f.cloth_hinge_offset[c]);
        for (std::size_t t = 0; t < fab.triangle_count(); ++t) {
            TriangleHinges th = fab.triangle_hinges()[t];
            for (std::int32_t& e : th.edge)
                if (e >= 0) e += ho;
            f.triangle_hinges.push_back(th);
            const auto& v = fab.triangles()[t].v;
            physics::ShellBendingRest<double> rest;
            (void)physics::shell_bending_rest(fab.rest_positions()[v[0]], fab.rest_positions()[v[1]], fab.rest_positions()[v[2]],
                                              rest);  // zero for a degenerate triangle: it bends nothing
            f.shell_rest.push_back(rest);
        }
        for (const Hinge& h0 : fab.hinges()) {
            Hinge h = h0;
            for (auto& v : h.v) v += vo;
            f.hinges.push_back(h);
            f.hinge_cloth.push_back(static_cast<std::uint32_t>(c));
        }
        const BlockPattern& fp = fab.pattern();
        for (std::size_t i = 0; i < fab.vertex_count(); ++i) {
            p.diagonal.push_back(fp.diagonal[i] + slot_offset);
            p.row_start.push_back(fp.row_start[i + 1] + slot_offset);
        }
        for (std::uint32_t col : fp.column) p.column.push_back(col + vo);
        for (std::uint32_t s : fp.triangle_slots) p.triangle_slots.push_back(s + slot_offset);
        for (std::uint32_t s : fp.hinge_slots) p.hinge_slots.push_back(s + slot_offset);

        // Pins: remember each pinned vertex's position in its motion's frame at t = 0.
        for (const PinDesc& pin : cloth.pins) {
            const std::uint32_t v = vo + pin.vertex;
            if (f.vertex_pin[v] >= 0) continue;  // pinned twice: keep the first
            Vec3d local = pin.position ? *pin.position : f.initial_positions[v];
            if (pin.collider >= 0) {
                const std::string where = "cloth '" + cloth.name + "': pin of vertex " + std::to_string(pin.vertex);
                if (pin.motion >= 0) throw Error(where + ": follows both a motion and a collider (expected one)");
                if (static_cast<std::size_t>(pin.collider) >= model.colliders.size())
                    throw Error(where + ": follows collider " + std::to_string(pin.collider) + " of " +
                                std::to_string(model.colliders.size()));
                const auto k = static_cast<std::size_t>(pin.collider);
                const ColliderDesc& followed = model.colliders[k];
                if (pin.collider_joint >= 0) {  // a bone: the pin's place in the joint's frame at t = 0
                    const std::size_t joints = followed.skin ? followed.skin->joints.size() : 0;
                    if (static_cast<std::size_t>(pin.collider_joint) >= joints)
                        throw Error(where + ": follows joint " + std::to_string(pin.collider_joint) + " of collider '" +
                                    followed.name + "', which has " +
                                    (joints == 0 ? std::string("no skin") : std::to_string(joints) + " joints"));
                    std::vector<Affine>& maps = start_maps[k];
                    if (maps.empty()) collider_mesh_transforms(followed, 0.0, maps);
                    local = inverse(maps[maps.size() == 1 ? 0 : static_cast<std::size_t>(pin.collider_joint)]).apply(local);
                } else {  // a skin vertex: the offset the pin keeps from it
                    if (followed.is_analytic() || !followed.mesh || pin.collider_vertex >= followed.mesh->positions.size())
                        throw Error(where + ": follows vertex " + std::to_string(pin.collider_vertex) + " of collider '" +
                                    followed.name + "', which " +
                                    (followed.is_analytic() || !followed.mesh
                                         ? std::string("is not a mesh")
                                         : "has " + std::to_string(followed.mesh->positions.size()) + " vertices"));
                    std::vector<Vec3d>& at_start = start_positions[k];
                    if (at_start.empty()) {
                        at_start.resize(followed.mesh->positions.size());
                        collider_mesh_positions(followed, 0.0, at_start);
                    }
                    local = local - at_start[pin.collider_vertex];
                }
            } else if (pin.motion >= 0) {
                const Transform frame = model.motions.at(static_cast<std::size_t>(pin.motion)).at(0.0);
                local = math::transpose(frame.rotation) * (local - frame.translation);
            }
            f.vertex_pin[v] = static_cast<std::int32_t>(f.pin_vertex.size());
            f.pin_vertex.push_back(v);
            f.pin_motion.push_back(pin.motion);
            f.pin_local.push_back(local);
            f.pin_collider.push_back(pin.collider);
            f.pin_collider_vertex.push_back(pin.collider_vertex);
            f.pin_collider_joint.push_back(pin.collider >= 0 ? pin.collider_joint : -1);
        }
    }

    build_gather_tables(f);
    return f;
}

std::size_t FlatModel::memory_bytes() const {
    const auto u32 = [](const std::vector<std::uint32_t>& v) { return v.capacity() * sizeof(std::uint32_t); };
    return u32(cloth_vertex_offset) + u32(cloth_triangle_offset) + u32(cloth_hinge_offset) +
           (initial_positions.capacity() + initial_velocities.capacity() + pin_local.capacity()) * sizeof(Vec3d) +
           mass.capacity() * sizeof(double) + u32(vertex_cloth) + triangles.capacity() * sizeof(Triangle) +
           triangle_rest.capacity() * sizeof(TriangleRest) + u32(triangle_cloth) + hinges.capacity() * sizeof(Hinge) +
           u32(hinge_cloth) + triangle_hinges.capacity() * sizeof(TriangleHinges) +
           shell_rest.capacity() * sizeof(physics::ShellBendingRest<double>) + u32(pattern.row_start) + u32(pattern.column) + u32(pattern.diagonal) +
           u32(pattern.triangle_slots) + u32(pattern.hinge_slots) + u32(vertex_force_start) +
           u32(vertex_force_index) + u32(slot_block_start) + u32(slot_block_index) + u32(pin_vertex) +
           (pin_motion.capacity() + pin_collider.capacity() + pin_collider_joint.capacity()) * sizeof(int) + pin_collider_vertex.capacity() * sizeof(std::uint32_t) +
           vertex_pin.capacity() * sizeof(std::int32_t);
}

std::pair<std::size_t, std::size_t> FlatModel::cloth_vertices(std::size_t cloth, std::size_t positions,
                                                             std::size_t velocities) const {
    if (cloth + 1 >= cloth_vertex_offset.size()) throw Error("cloth index " + std::to_string(cloth) + " out of range");
    const std::size_t first = cloth_vertex_offset[cloth];
    const std::size_t count = cloth_vertex_offset[cloth + 1] - first;
    if (positions != count || velocities != count)
        throw Error("cloth " + std::to_string(cloth) + ": state size mismatch (" + std::to_string(count) +
                    " vertices, got " + std::to_string(positions) + " positions and " + std::to_string(velocities) +
                    " velocities)");
    return {first, count};
}

void pin_targets(const Model& model, const FlatModel& f, double t, std::span<Vec3d> out) {
    if (out.size() != f.pin_vertex.size())
        throw Error("pin_targets: " + std::to_string(out.size()) + " outputs for " + std::to_string(f.pin_vertex.size()) + " pins");
    // A character's vertices are skinned (or its joint maps formed) once per collider, not once per pin.
    std::vector<std::vector<Vec3d>> skinned(model.colliders.size());
    std::vector<std::vector<Affine>> maps(model.colliders.size());
    for (std::size_t q = 0; q < f.pin_vertex.size(); ++q) {
        const int c = q < f.pin_collider.size() ? f.pin_collider[q] : -1;
        const int joint = q < f.pin_collider_joint.size() ? f.pin_collider_joint[q] : -1;
        if (c >= 0 && joint >= 0) {
            std::vector<Affine>& a = maps[static_cast<std::size_t>(c)];
            if (a.empty()) collider_mesh_transforms(model.colliders[static_cast<std::size_t>(c)], t, a);
            out[q] = a[a.size() == 1 ? 0 : static_cast<std::size_t>(joint)].apply(f.pin_local[q]);
        } else if (c >= 0) {
            std::vector<Vec3d>& x = skinned[static_cast<std::size_t>(c)];
            const ColliderDesc& collider = model.colliders[static_cast<std::size_t>(c)];
            if (x.empty()) {
                x.resize(collider.mesh->positions.size());
                collider_mesh_positions(collider, t, x);
            }
            out[q] = x[f.pin_collider_vertex[q]] + f.pin_local[q];
        } else if (f.pin_motion[q] >= 0) {
            out[q] = model.motions[static_cast<std::size_t>(f.pin_motion[q])].at(t).apply(f.pin_local[q]);
        } else {
            out[q] = f.pin_local[q];
        }
    }
}

}  // namespace weft
