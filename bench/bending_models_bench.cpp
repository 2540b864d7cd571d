// Which discrete bending energy converges? The clamped strip of weft_bending_bench, solved to static
// equilibrium outside the simulator (Newton on the total energy, a banded Cholesky, double) for
// candidate bending energies, against the exact heavy elastica. Measures the candidates before one
// of them replaces the solver's model (issue 22):
//
//   hinge    the solver's default: ½·D·Σ_e w_e·θ_e² over interior edges, w_e = |e|²/(A₀+A₁)
//            (weft/physics/bending.h's hinge_weight);
//   shell    (solver.bending = "shell") a shape operator per triangle from its three edges' angles,
//            S_f = Σ_i θ_i·|e_i|/(2·A_f)·t_i t_iᵀ (t_i the unit in-plane normal of edge i at rest), and
//            the plate energy ½·D·Σ_f A_f·|S_f|²_F (Poisson 0). A cylinder bent about either grid axis
//            costs the plate energy; about the grid's diagonal 1.49× (so does the hinge model's);
//   midedge  (solver.bending = "midedge") the shell model with each edge's normal free to turn about
//            the edge, ψ_i = θ_i + 2·s_i·ξ_e (weft/physics/midedge_bending.h); here the turns ξ are
//            unknowns of the Newton solve beside the positions (the solver relaxes them by a CG solve
//            at each linearisation point instead: runtime/src/midedge_normals.h), so this is the
//            model's exact static answer. The cylinder costs the plate energy about any direction.
//
// Each model runs on grids (cells of the given aspect) and on the strip meshed with its rows at 45°.
// It also prints each energy of a cylinder bent about the grid's axes and its diagonal, over the
// plate's ½·D·κ²·area (1 is exact; a free sheet's edges make it 1 − O(1/n)).
//
//   weft_bending_models_bench [--cells 12,24,48] [--aspect 0.5,1,2] [--load 0.5,2,6.6] [--json FILE]
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "diagonal_strip.h"
#include "heavy_elastica.h"
#include "json_file.h"
#include "json_writer.h"
#include "strip_sweep_args.h"
#include "weft/error.h"
#include "weft/physics/bending.h"
#include "weft/physics/membrane.h"
#include "weft/physics/midedge_bending.h"
#include "weft/physics/shell_bending.h"
#include "midedge_normals.h"

namespace {

using weft::physics::HessianKind;
using V3 = weft::physics::Vec3<double>;
using M3 = weft::physics::Mat3<double>;

constexpr double kLength = 0.3, kWidth = 0.04, kDensity = 0.2, kGravity = 9.81, kStretch = 1e6;

enum class Model { Hinge, Shell, MidEdge };
const char* name(Model m) {
    return m == Model::Hinge ? "hinge" : m == Model::Shell ? "shell" : "midedge";
}

/// A grid strip, vertex (i, j) at index i·(ny + 1) + j (numbered across first, so that the stiffness
/// matrix is banded), cells split along alternating diagonals as weft::make_grid does. The clamp: the
/// first `pinned` vertices (two columns); the tip: the vertices of the last column.
struct Strip {
    int nx = 0, ny = 0;  // cells along, across
    std::vector<V3> rest;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    std::size_t pinned = 0;
    std::vector<std::uint32_t> tip;
    double column_step = 0.0;  ///< m between the two clamped columns
    [[nodiscard]] std::uint32_t id(int i, int j) const { return static_cast<std::uint32_t>(i * (ny + 1) + j); }
};

/// The strip meshed with its rows at 45° (tests/common/diagonal_strip.h), as a Strip: its clamp is
/// its first vertices.
Strip make_diagonal_strip(int columns, double length, double width) {
    const weft::test::DiagonalStrip d = weft::test::make_diagonal_strip(columns, length, width);
    Strip s;
    s.rest = d.mesh.positions;
    for (const weft::Triangle& t : d.mesh.triangles) s.triangles.push_back({t.v[0], t.v[1], t.v[2]});
    s.pinned = d.clamp.size();
    for (std::size_t i = 0; i < d.clamp.size(); ++i)
        if (d.clamp[i] != i) throw weft::Error("diagonal strip: the clamp is not the first vertices");
    s.tip = d.tip;
    s.column_step = d.column_step;
    return s;
}

Strip make_strip(int nx, int ny, double length, double width) {
    Strip s;
    s.nx = nx;
    s.ny = ny;
    for (int i = 0; i <= nx; ++i)
        for (int j = 0; j <= ny; ++j) s.rest.push_back({length * i / nx, 0.0, width * j / ny});
    s.pinned = 2 * static_cast<std::size_t>(ny + 1);
    for (int j = 0; j <= ny; ++j) s.tip.push_back(s.id(nx, j));
    s.column_step = length / nx;
    for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j) {
            // Oriented so that the normal points up (+y): (x along, z across) has x × z = −y, so the
            // corners go a, c, d … (counter-clockwise seen from above).
            const std::uint32_t a = s.id(i, j), b = s.id(i + 1, j), c = s.id(i, j + 1), d = s.id(i + 1, j + 1);
            if (((i + j) & 1) == 0) {
                s.triangles.push_back({a, d, b});
                s.triangles.push_back({a, c, d});
            } else {
                s.triangles.push_back({a, c, b});
                s.triangles.push_back({b, c, d});
            }
        }
    return s;
}

/// Interior edges as hinges (x0, x1 the edge as it runs in the first triangle, x2 its far corner, x3
/// the other triangle's), and per triangle the hinge of each of its edges (−1 on the boundary).
struct Topology {
    std::vector<std::array<std::uint32_t, 4>> hinges;
    std::vector<std::array<int, 3>> face_hinges;
};

Topology build_topology(const Strip& s) {
    Topology t;
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<std::size_t, int>> first;  // edge → (triangle, corner)
    t.face_hinges.assign(s.triangles.size(), {-1, -1, -1});
    for (std::size_t f = 0; f < s.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t u = s.triangles[f][k], v = s.triangles[f][(k + 1) % 3];
            const auto key = std::minmax(u, v);
            const auto it = first.find(key);
            if (it == first.end()) {
                first[key] = {f, k};
                continue;
            }
            const auto [g, kg] = it->second;
            const std::uint32_t x0 = s.triangles[g][kg], x1 = s.triangles[g][(kg + 1) % 3];
            t.hinges.push_back({x0, x1, s.triangles[g][(kg + 2) % 3], s.triangles[f][(k + 2) % 3]});
            t.face_hinges[g][kg] = static_cast<int>(t.hinges.size() - 1);
            t.face_hinges[f][k] = static_cast<int>(t.hinges.size() - 1);
        }
    return t;
}

/// Rest data of the shell model (weft/physics/shell_bending.h), per triangle.
std::vector<weft::physics::ShellBendingRest<double>> face_rest(const Strip& s) {
    std::vector<weft::physics::ShellBendingRest<double>> out(s.triangles.size());
    for (std::size_t f = 0; f < s.triangles.size(); ++f)
        (void)weft::physics::shell_bending_rest(s.rest[s.triangles[f][0]], s.rest[s.triangles[f][1]], s.rest[s.triangles[f][2]],
                                                out[f]);
    return out;
}

/// The bending energy of `x` (rest flat) and, when asked, its gradient and a positive semi-definite
/// Hessian (Gauss–Newton: the angles' second derivatives dropped), added into `grad` and `hess`.
struct Bending {
    Model model;
    double stiffness;
    const Strip* strip;
    Topology topo;
    std::vector<double> hinge_weight;
    std::vector<weft::physics::ShellBendingRest<double>> faces;
    // The mid-edge model's view of the strip in the runtime's types, and its state.
    std::vector<weft::Triangle> triangles;
    std::vector<weft::TriangleHinges> triangle_hinges;
    std::vector<weft::Hinge> hinges;
    mutable weft::MidEdgeState midedge;

    void prepare_midedge() {
        for (const auto& t : strip->triangles) triangles.push_back(weft::Triangle{{t[0], t[1], t[2]}});
        for (const auto& fh : topo.face_hinges) triangle_hinges.push_back(weft::TriangleHinges{{fh[0], fh[1], fh[2]}});
        for (const auto& h : topo.hinges) hinges.push_back(weft::Hinge{{h[0], h[1], h[2], h[3]}, 0.0, 0.0});
        weft::midedge_rest(faces, triangle_hinges, midedge.rest);
        weft::midedge_hinge_faces(triangle_hinges, hinges.size(), midedge.hinge_faces);
    }

    /// The mid-edge model's triangles at positions `x` (runtime/src/midedge_normals.h, as the solver
    /// builds them: the clamp from the pinned vertices).
    void midedge_state(const std::vector<V3>& x, weft::MidEdgeState& st) const {
        weft::midedge_faces(triangles, triangle_hinges, hinges, [&](std::uint32_t i) { return x[i]; },
                            [&](std::uint32_t i) { return i < strip->pinned; }, st.angle, st.faces);
    }

    double evaluate(const std::vector<V3>& x, std::vector<V3>* grad,
                    const std::function<void(std::uint32_t, std::uint32_t, const M3&)>* add) const {
        const std::size_t nh = topo.hinges.size();
        std::vector<double> theta(nh, 0.0);
        std::vector<std::array<V3, 4>> dtheta(nh);
        for (std::size_t h = 0; h < nh; ++h) {
            V3 p[4];
            for (int a = 0; a < 4; ++a) p[a] = x[topo.hinges[h][a]];
            theta[h] = weft::physics::dihedral_angle(p);
            V3 d[4];
            (void)weft::physics::dihedral_angle_derivatives<double>(p, d, nullptr);
            for (int a = 0; a < 4; ++a) dtheta[h][a] = d[a];
        }
        double energy = 0.0;
        // ∂E/∂θ_h, and the Gauss–Newton couplings Σ K_hk ∇θ_h ∇θ_kᵀ.
        std::vector<double> de(nh, 0.0);
        std::vector<std::pair<std::pair<int, int>, double>> couplings;
        if (model == Model::MidEdge) {
            // The normals relaxed at x (the solver's solve), then the triangles' energy.
            midedge_state(x, midedge);
            midedge.xi.assign(nh, 0.0);
            midedge.report = weft::solve_midedge_normals(midedge.faces, midedge.rest, midedge.hinge_faces, midedge.xi, midedge.scratch);
            for (std::size_t f = 0; f < faces.size(); ++f) {
                bool present[3];
                V3 p[3][4];
                const double rest_angle[3] = {0.0, 0.0, 0.0};
                for (int k = 0; k < 3; ++k) {
                    present[k] = topo.face_hinges[f][k] >= 0;
                    for (int a = 0; a < 4; ++a) p[k][a] = present[k] ? x[topo.hinges[topo.face_hinges[f][k]][a]] : V3{};
                }
                const auto reading = midedge.reading(f);
                energy += weft::physics::shell_bending_evaluate(stiffness, midedge.rest[f], present, p, rest_angle, &reading).energy;
            }
            return energy;
        } else if (model == Model::Hinge) {
            for (std::size_t h = 0; h < nh; ++h) {
                const double k = stiffness * hinge_weight[h];
                energy += 0.5 * k * theta[h] * theta[h];
                de[h] = k * theta[h];
                couplings.push_back({{static_cast<int>(h), static_cast<int>(h)}, k});
            }
        } else {
            // Through the shared physics (weft/physics/shell_bending.h): each triangle's ∂E/∂θ of its
            // hinges and its Gauss–Newton couplings.
            for (std::size_t f = 0; f < faces.size(); ++f) {
                const auto& fh = topo.face_hinges[f];
                bool present[3];
                V3 p[3][4];
                const double rest_angle[3] = {0.0, 0.0, 0.0};
                for (int k = 0; k < 3; ++k) {
                    present[k] = fh[k] >= 0;
                    for (int a = 0; a < 4; ++a) p[k][a] = present[k] ? x[topo.hinges[fh[k]][a]] : V3{};
                }
                const auto t = weft::physics::shell_bending_evaluate(stiffness, faces[f], present, p, rest_angle);
                energy += t.energy;
                for (int k = 0; k < 3; ++k) {
                    if (!t.active[k]) continue;
                    de[fh[k]] += t.force_angle[k];
                    for (int l = 0; l < 3; ++l)
                        if (t.active[l])
                            couplings.push_back({{fh[k], fh[l]}, weft::physics::shell_bending_coupling(stiffness, faces[f], k, l)});
                }
            }
        }
        if (grad != nullptr)
            for (std::size_t h = 0; h < nh; ++h)
                for (int a = 0; a < 4; ++a) (*grad)[topo.hinges[h][a]] += de[h] * dtheta[h][a];
        if (add != nullptr)
            for (const auto& [hk, k] : couplings)
                for (int a = 0; a < 4; ++a)
                    for (int b = 0; b < 4; ++b)
                        (*add)(topo.hinges[hk.first][a], topo.hinges[hk.second][b],
                               k * M3::outer(dtheta[hk.first][a], dtheta[hk.second][b]));
        return energy;
    }
};

/// A symmetric banded matrix over 3 dofs a vertex and its Cholesky factorisation in place.
struct Banded {
    std::size_t n = 0, band = 0;  // dofs, half-bandwidth
    std::vector<double> a;        // row r, column c ≥ r − band: a[r·(band + 1) + (c − r + band)] for c ≤ r
    void reset(std::size_t dofs, std::size_t half) {
        n = dofs;
        band = half;
        a.assign(n * (band + 1), 0.0);
    }
    double& at(std::size_t r, std::size_t c) { return a[r * (band + 1) + (c + band - r)]; }  // c ≤ r
    void add(std::size_t r, std::size_t c, double v) {
        if (c > r) return;  // the lower triangle holds the matrix
        if (r - c > band) throw weft::Error("banded matrix: entry outside the band");
        at(r, c) += v;
    }
    bool factor() {
        for (std::size_t j = 0; j < n; ++j) {
            const std::size_t lo = j > band ? j - band : 0;
            double d = at(j, j);
            for (std::size_t k = lo; k < j; ++k) d -= at(j, k) * at(j, k);
            if (!(d > 0.0)) return false;
            d = std::sqrt(d);
            at(j, j) = d;
            for (std::size_t i = j + 1; i < std::min(n, j + band + 1); ++i) {
                const std::size_t lo_i = i > band ? i - band : 0;
                double s = at(i, j);
                for (std::size_t k = std::max(lo, lo_i); k < j; ++k) s -= at(i, k) * at(j, k);
                at(i, j) = s / d;
            }
        }
        return true;
    }
    void solve(std::vector<double>& b) {
        for (std::size_t i = 0; i < n; ++i) {
            const std::size_t lo = i > band ? i - band : 0;
            for (std::size_t k = lo; k < i; ++k) b[i] -= at(i, k) * b[k];
            b[i] /= at(i, i);
        }
        for (std::size_t i = n; i-- > 0;) {
            for (std::size_t k = i + 1; k < std::min(n, i + band + 1); ++k) b[i] -= at(k, i) * b[k];
            b[i] /= at(i, i);
        }
    }
};

struct Row {
    Model model = Model::Hinge;
    double load = 0.0, aspect = 0.0;
    int cells_along = 0, cells_across = 0;
    double deflection = 0.0, reference = 0.0, error = 0.0, seconds = 0.0;
    /// Against the elastica of free length L − dx/2: a hinge at the clamp's second column stands for
    /// the curvature of the half cell on either side of it, so the continuum clamp sits half a cell in.
    double reference_mid = 0.0, error_mid = 0.0;
    int newton = 0;
    double residual = 0.0;  ///< the largest free-vertex force left, over one vertex's weight
};

/// The strip clamped by its first two columns, at rest under its weight: Newton with a backtracking
/// line search on the total energy, the weight ramped in over five stages.
Row solve(Model model, double load, int cells_along, double aspect, bool diagonal = false) {
    Row row;
    row.model = model;
    row.load = load;
    row.cells_along = cells_along;
    double dx = kLength / cells_along;
    row.cells_across = std::max(2, static_cast<int>(std::lround(kWidth / (dx / aspect))));
    row.aspect = dx / (kWidth / row.cells_across);
    const auto start = std::chrono::steady_clock::now();
    const Strip s = diagonal ? make_diagonal_strip(cells_along, kLength, kWidth) : make_strip(cells_along, row.cells_across, kLength, kWidth);
    dx = s.column_step;
    if (diagonal) {
        row.cells_across = -1;  // rows at 45°: printed as such
        row.aspect = 1.0;
    }
    Bending bending{model, kDensity * kGravity * kLength * kLength * kLength / load, &s, build_topology(s), {}, {}};
    for (const auto& h : bending.topo.hinges) {
        V3 p[4];
        for (int a = 0; a < 4; ++a) p[a] = s.rest[h[a]];
        bending.hinge_weight.push_back(weft::physics::hinge_weight(p));
    }
    bending.faces = face_rest(s);
    if (model == Model::MidEdge) bending.prepare_midedge();
    const auto material = weft::physics::membrane_material(kStretch, 0.0);
    std::vector<std::array<std::array<double, 2>, 2>> dm(s.triangles.size());
    std::vector<double> area(s.triangles.size());
    std::vector<double> mass(s.rest.size(), 0.0);
    for (std::size_t f = 0; f < s.triangles.size(); ++f) {
        double d[2][2];
        (void)weft::physics::membrane_rest(s.rest[s.triangles[f][0]], s.rest[s.triangles[f][1]], s.rest[s.triangles[f][2]], d,
                                           area[f]);
        dm[f] = {{{d[0][0], d[0][1]}, {d[1][0], d[1][1]}}};
        for (int k = 0; k < 3; ++k) mass[s.triangles[f][k]] += kDensity * area[f] / 3.0;
    }
    const std::size_t nv = s.rest.size();
    // Free vertices: every column but the first two; dof 3·(v − pinned) + c.
    const std::size_t pinned = s.pinned;
    const std::size_t dofs = 3 * (nv - pinned);
    // Half-bandwidth: the widest coupling (the shell model's far corners are two rows apart).
    std::size_t span = 0;
    for (const auto& h : bending.topo.hinges)
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) span = std::max<std::size_t>(span, h[a] > h[b] ? h[a] - h[b] : h[b] - h[a]);
    // The shell model couples the far corners of a triangle's hinges, which share its corners: at
    // most two hinge spans apart.
    if (model != Model::Hinge) span = 2 * span;
    Banded hess;
    (void)span;
    (void)dofs;

    // Unknowns: three a free vertex and (the mid-edge model) one a hinge whose normal may turn (not
    // held by a clamp), numbered along the strip (by rest x, a hinge at its edge's midpoint) so that
    // the matrix stays banded. The mid-edge model's boundary normals are condensed out at rest.
    const bool midedge = model == Model::MidEdge;
    const std::size_t ne = midedge ? bending.hinges.size() : 0;
    constexpr std::size_t kNone = static_cast<std::size_t>(-1);
    std::vector<std::size_t> vdof(nv, kNone), edof(ne, kNone);
    std::size_t unknowns = 0;
    {
        std::vector<char> turns(ne, 0);
        if (midedge) {
            bending.midedge_state(s.rest, bending.midedge);
            for (const auto& f : bending.midedge.faces)
                for (int k = 0; k < 3; ++k)
                    if (f.side[k] != 0.0) turns[static_cast<std::size_t>(f.hinge[k])] = 1;
        }
        std::vector<std::pair<double, std::int64_t>> order;  // (x, vertex ≥ 0 or −1 − hinge)
        for (std::size_t v = pinned; v < nv; ++v) order.push_back({s.rest[v].x, static_cast<std::int64_t>(v)});
        for (std::size_t e = 0; e < ne; ++e)
            if (turns[e] != 0) {
                const auto& hv = bending.hinges[e].v;
                order.push_back({0.5 * (s.rest[hv[0]].x + s.rest[hv[1]].x), -1 - static_cast<std::int64_t>(e)});
            }
        std::stable_sort(order.begin(), order.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
        for (const auto& [key, node] : order) {
            if (node >= 0) {
                vdof[static_cast<std::size_t>(node)] = unknowns;
                unknowns += 3;
            } else {
                edof[static_cast<std::size_t>(-1 - node)] = unknowns++;
            }
        }
    }

    std::vector<V3> x = s.rest;
    std::vector<double> xi(ne, 0.0);
    double gravity = 0.0;
    std::size_t band = 0;
    bool probing = false;
    const auto put = [&](Banded* h, std::size_t r, std::size_t c, double v) {
        if (r == kNone || c == kNone) return;
        if (probing) {
            band = std::max(band, r > c ? r - c : c - r);
            return;
        }
        h->add(r, c, v);
    };
    const auto total = [&](const std::vector<V3>& p, const std::vector<double>& q, std::vector<V3>* grad, std::vector<double>* gxi,
                           Banded* h) {
        double e = 0.0;
        std::function<void(std::uint32_t, std::uint32_t, const M3&)> add = [&](std::uint32_t a, std::uint32_t b, const M3& m) {
            if (vdof[a] == kNone || vdof[b] == kNone) return;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c)
                    put(h, vdof[a] + static_cast<std::size_t>(r), vdof[b] + static_cast<std::size_t>(c), m.m[r][c]);
        };
        for (std::size_t f = 0; f < s.triangles.size(); ++f) {
            const V3 tq[3] = {p[s.triangles[f][0]], p[s.triangles[f][1]], p[s.triangles[f][2]]};
            const double d[2][2] = {{dm[f][0][0], dm[f][0][1]}, {dm[f][1][0], dm[f][1][1]}};
            V3 g[3];
            M3 hh[3][3];
            e += weft::physics::membrane_evaluate(d, area[f], material, tq, g, h != nullptr ? hh : nullptr, HessianKind::Fast);
            for (int a2 = 0; a2 < 3; ++a2) {
                if (grad != nullptr) (*grad)[s.triangles[f][a2]] += g[a2];
                if (h != nullptr)
                    for (int b2 = 0; b2 < 3; ++b2) add(s.triangles[f][a2], s.triangles[f][b2], hh[a2][b2]);
            }
        }
        if (midedge) {
            // E(θ(x), ξ) with ξ unknowns, through the shared physics (weft/physics/midedge_bending.h):
            // each triangle's reading at ξ, its energy and ∂E/∂θ, ∂E/∂ξ, and the Gauss–Newton blocks
            // over ψ_k = a_k·θ_k + 2·s_k·ξ_k.
            weft::MidEdgeState& st = bending.midedge;
            bending.midedge_state(p, st);
            for (std::size_t f = 0; f < bending.faces.size(); ++f) {
                const auto& face = st.faces[f];
                const auto& rest = st.rest[f];
                double local[3]{};
                bool present[3];
                V3 pts[3][4];
                const double rest_angle[3] = {0.0, 0.0, 0.0};
                for (int k = 0; k < 3; ++k) {
                    present[k] = face.hinge[k] >= 0;
                    if (face.side[k] != 0.0) local[k] = q[static_cast<std::size_t>(face.hinge[k])];
                    for (int a2 = 0; a2 < 4; ++a2)
                        pts[k][a2] = present[k] ? p[bending.hinges[static_cast<std::size_t>(face.hinge[k])].v[a2]] : V3{};
                }
                const auto reading = weft::physics::midedge_reading(face, local);
                const auto t = weft::physics::shell_bending_evaluate(bending.stiffness, rest, present, pts, rest_angle, &reading);
                e += t.energy;
                const double scale = bending.stiffness * rest.area;
                for (int k = 0; k < 3; ++k) {
                    const auto* hv = present[k] ? bending.hinges[static_cast<std::size_t>(face.hinge[k])].v : nullptr;
                    if (grad != nullptr && t.active[k])
                        for (int a2 = 0; a2 < 4; ++a2) (*grad)[hv[a2]] += t.force_angle[k] * t.dtheta[k][a2];
                    if (gxi != nullptr && face.side[k] != 0.0)
                        (*gxi)[static_cast<std::size_t>(face.hinge[k])] += scale * weft::physics::midedge_xi_gradient(face, rest, local, k, true);
                    if (h == nullptr) continue;
                    for (int l = 0; l < 3; ++l) {
                        const double c = scale * rest.m[k][l];
                        const std::size_t ek = face.side[k] != 0.0 ? edof[static_cast<std::size_t>(face.hinge[k])] : kNone;
                        const std::size_t el = face.side[l] != 0.0 ? edof[static_cast<std::size_t>(face.hinge[l])] : kNone;
                        put(h, ek, el, c * 4.0 * face.side[k] * face.side[l]);
                        if (!t.active[k]) continue;
                        for (int a2 = 0; a2 < 4; ++a2) {
                            if (t.active[l]) {
                                const auto* lv = bending.hinges[static_cast<std::size_t>(face.hinge[l])].v;
                                for (int b2 = 0; b2 < 4; ++b2)
                                    add(hv[a2], lv[b2], (c * face.scale[k] * face.scale[l]) * M3::outer(t.dtheta[k][a2], t.dtheta[l][b2]));
                            }
                            const std::size_t r0 = vdof[hv[a2]];
                            if (r0 == kNone || el == kNone) continue;
                            const double w = c * face.scale[k] * 2.0 * face.side[l];
                            for (int r = 0; r < 3; ++r) {
                                put(h, r0 + static_cast<std::size_t>(r), el, w * t.dtheta[k][a2][r]);
                                put(h, el, r0 + static_cast<std::size_t>(r), w * t.dtheta[k][a2][r]);
                            }
                        }
                    }
                }
            }
        } else {
            e += bending.evaluate(p, grad, h != nullptr ? &add : nullptr);
        }
        for (std::size_t v = 0; v < nv; ++v) {
            e += mass[v] * gravity * p[v].y;
            if (grad != nullptr) (*grad)[v].y += mass[v] * gravity;
        }
        return e;
    };
    {
        probing = true;
        std::vector<V3> grad(nv);
        std::vector<double> gxi(ne);
        (void)total(x, xi, &grad, &gxi, &hess);
        probing = false;
    }
    const double vertex_weight = kDensity * kGravity * kLength * kWidth / static_cast<double>(nv);
    for (int stage = 1; stage <= 5; ++stage) {
        gravity = kGravity * stage / 5.0;
        for (int it = 0; it < 200; ++it) {
            std::vector<V3> grad(nv);
            std::vector<double> gxi(ne, 0.0);
            hess.reset(unknowns, band);
            const double e0 = total(x, xi, &grad, &gxi, &hess);
            std::vector<double> g(unknowns);
            double largest = 0.0, largest_xi = 0.0;
            for (std::size_t v = pinned; v < nv; ++v)
                for (int c = 0; c < 3; ++c) {
                    g[vdof[v] + static_cast<std::size_t>(c)] = -grad[v][c];
                    largest = std::max(largest, std::abs(grad[v][c]));
                }
            for (std::size_t e2 = 0; e2 < ne; ++e2) {
                if (edof[e2] == kNone) continue;
                g[edof[e2]] = -gxi[e2];
                largest_xi = std::max(largest_xi, std::abs(gxi[e2]));
            }
            row.residual = largest / vertex_weight;
            // ξ's force is a moment (N·m): against the vertex weight over a cell.
            if (largest < 1e-6 * vertex_weight && largest_xi < 1e-6 * vertex_weight * dx) break;
            double diag = 0.0;
            for (std::size_t r = 0; r < unknowns; ++r) diag = std::max(diag, hess.at(r, r));
            for (std::size_t r = 0; r < unknowns; ++r) hess.at(r, r) += 1e-14 * diag;
            if (!hess.factor()) throw weft::Error(std::string(name(model)) + ": the Hessian is not positive definite");
            hess.solve(g);
            double step = 1.0;
            std::vector<V3> trial(nv);
            std::vector<double> trial_xi(ne);
            for (int ls = 0; ls < 40; ++ls, step *= 0.5) {
                trial = x;
                trial_xi = xi;
                for (std::size_t v = pinned; v < nv; ++v)
                    for (int c = 0; c < 3; ++c) trial[v][c] += step * g[vdof[v] + static_cast<std::size_t>(c)];
                for (std::size_t e2 = 0; e2 < ne; ++e2)
                    if (edof[e2] != kNone) trial_xi[e2] += step * g[edof[e2]];
                if (total(trial, trial_xi, nullptr, nullptr, nullptr) <= e0) break;
            }
            x = trial;
            xi = trial_xi;
            ++row.newton;
        }
    }
    double tip = 0.0;
    for (const std::uint32_t v : s.tip) tip += x[v].y;
    row.deflection = -tip / static_cast<double>(s.tip.size());
    row.reference = weft::test::heavy_elastica_deflection(load / (kLength * kLength * kLength), kLength - dx);
    row.error = (row.deflection - row.reference) / row.reference;
    row.reference_mid = weft::test::heavy_elastica_deflection(load / (kLength * kLength * kLength), kLength - 0.5 * dx);
    row.error_mid = (row.deflection - row.reference_mid) / row.reference_mid;
    row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return row;
}

/// Each model's energy of a 40 × 40 sheet bent into a cylinder of curvature κ about direction
/// `angle` (radians from the grid's x axis), over the plate's ½·D·κ²·area.
double cylinder_ratio(Model model, double angle) {
    const int n = 40;
    const double size = 0.4, kappa = 2.0, stiffness = 1.0;
    Strip s = make_strip(n, n, size, size);
    s.pinned = 0;  // a free sheet: no clamp for the mid-edge model
    Bending bending{model, stiffness, &s, build_topology(s), {}, {}};
    for (const auto& h : bending.topo.hinges) {
        V3 p[4];
        for (int a = 0; a < 4; ++a) p[a] = s.rest[h[a]];
        bending.hinge_weight.push_back(weft::physics::hinge_weight(p));
    }
    bending.faces = face_rest(s);
    if (model == Model::MidEdge) bending.prepare_midedge();
    // The cylinder's axis runs along (cos a, 0, sin a); the sheet wraps about it, away from +y.
    const V3 axis{std::cos(angle), 0.0, std::sin(angle)}, across{-std::sin(angle), 0.0, std::cos(angle)};
    std::vector<V3> x(s.rest.size());
    const V3 centre{0.5 * size, 0.0, 0.5 * size};
    for (std::size_t v = 0; v < x.size(); ++v) {
        const V3 d = s.rest[v] - centre;
        const double along = weft::physics::dot(d, axis), u = weft::physics::dot(d, across);
        const double phi = kappa * u;
        x[v] = centre + along * axis + (std::sin(phi) / kappa) * across + V3{0.0, (1.0 - std::cos(phi)) / kappa, 0.0};
    }
    const double e = bending.evaluate(x, nullptr, nullptr);
    return e / (0.5 * stiffness * kappa * kappa * size * size);
}


}  // namespace

int main(int argc, char** argv) {
    try {
        const weft::bench::StripSweep sweep = weft::bench::parse_strip_sweep(argc, argv);
        std::printf("cylinder energy over the plate's ½·D·κ²·area (40 × 40 sweep.cells), bent about the grid's x axis / z axis / "
                    "diagonal:\n");
        for (const Model m : {Model::Hinge, Model::Shell, Model::MidEdge})
            std::printf("  %-5s %.3f / %.3f / %.3f\n", name(m), cylinder_ratio(m, 0.0), cylinder_ratio(m, std::numbers::pi / 2.0),
                        cylinder_ratio(m, std::numbers::pi / 4.0));
        std::printf("\n| model | load ρgL³/D | cells along × across | cell aspect | tip deflection m | heavy elastica m (L − dx) | "
                    "error | error against L − dx/2 | Newton steps | force left / vertex weight | s |\n"
                    "|---|---|---|---|---|---|---|---|---|---|---|\n");
        std::vector<Row> rows;
        const auto print = [](const Row& r) {
            const std::string mesh = r.cells_across < 0 ? std::to_string(r.cells_along) + " columns, rows at 45°"
                                                        : std::to_string(r.cells_along) + " × " + std::to_string(r.cells_across);
            std::printf("| %s | %.2g | %s | %.2f | %.5f | %.5f | %+.2f%% | %+.2f%% | %d | %.1e | %.1f |\n", name(r.model), r.load,
                        mesh.c_str(), r.aspect, r.deflection, r.reference, 100.0 * r.error, 100.0 * r.error_mid, r.newton, r.residual,
                        r.seconds);
            std::fflush(stdout);
        };
        for (const double load : sweep.loads) {
            for (const double aspect : sweep.aspects)
                for (const double n : sweep.cells)
                    for (const Model m : {Model::Hinge, Model::Shell, Model::MidEdge}) {
                        rows.push_back(solve(m, load, static_cast<int>(n), aspect));
                        print(rows.back());
                    }
            // The same strip meshed with its rows at 45° (an even number of lattice columns).
            for (const double n : sweep.cells)
                for (const Model m : {Model::Hinge, Model::Shell, Model::MidEdge}) {
                    rows.push_back(solve(m, load, 2 * (static_cast<int>(n) / 2), 1.0, true));
                    print(rows.back());
                }
        }
        if (!sweep.json.empty() &&
            !weft::bench::write_json_file(sweep.json, "weft_bending_models_bench", [&](std::ostream& out) {
                weft::json::JsonWriter json(out);
                json.begin_array();
                for (const Row& r : rows)
                    json.begin_object()
                        .field("model", name(r.model))
                        .field("mesh", r.cells_across < 0 ? "rows at 45 degrees" : "grid")
                        .field("load", r.load)
                        .field("cells_along", r.cells_along)
                        .field("cells_across", r.cells_across)
                        .field("aspect", r.aspect)
                        .field("deflection_m", r.deflection)
                        .field("elastica_m", r.reference)
                        .field("error", r.error)
                        .field("elastica_half_cell_m", r.reference_mid)
                        .field("error_half_cell", r.error_mid)
                        .field("newton", r.newton)
                        .field("seconds", r.seconds)
                        .end_object();
                json.end_array();
            }))
            return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "weft_bending_models_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
