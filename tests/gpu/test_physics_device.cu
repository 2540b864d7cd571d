// The single-source physics functions (runtime/include/weft/physics/) evaluated in float on the GPU
// agree with the same functions evaluated in float on the host. The CUDA backend relies on this: its
// kernels call exactly these functions, and the CPU backend is the reference.
//
// Both sides are compiled without FMA contraction (--fmad=false for the device, -ffp-contract=off for
// the host part of this file), and + − × ÷ √ are correctly rounded in both, so most results agree to
// the bit; only library functions whose rounding differs (atan2 in the dihedral angle: CUDA's atan2f
// is accurate to 3 ulp, glibc's to 1) may differ by a few ulps. The tolerance, 1e-5 of the magnitude
// of each quantity (about 80 float ulps), leaves room for those while catching any real divergence
// (a branch taken differently, a host-only code path, uninitialised memory), which shows up as
// errors of order 1. Inputs are random but well conditioned, so a few ulps in an input cannot be
// amplified: no near-degenerate triangles, bending angles away from the rest angle and from ±π,
// contact distances away from the contact threshold and from shape medial axes.
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "weft/physics/aerodynamics.h"
#include "weft/physics/bending.h"
#include "weft/physics/collider_contact.h"
#include "weft/physics/hessian.h"
#include "weft/physics/membrane.h"

#include "gpu_test_util.h"

namespace weft::physics {
namespace {

using V = Vec3<float>;
using M = Mat3<float>;

constexpr int kCases = 1000;
constexpr double kRelTol = 1e-5;

// ---- running functions on the device ------------------------------------------------------------

void check(cudaError_t err, const char* what) {
    if (err == cudaSuccess) return;
    throw std::runtime_error(std::string(what) + ": " + cudaGetErrorName(err) + " (" + cudaGetErrorString(err) + ")");
}

struct DeviceFree {
    void operator()(void* p) const { cudaFree(p); }
};

template <typename T>
std::unique_ptr<T, DeviceFree> device_alloc(std::size_t count) {
    void* p = nullptr;
    check(cudaMalloc(&p, count * sizeof(T)), "cudaMalloc");
    return std::unique_ptr<T, DeviceFree>(static_cast<T*>(p));
}

template <typename Eval>
__global__ void evaluate_kernel(const typename Eval::Case* in, typename Eval::Out* out, unsigned n) {
    const unsigned i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i < n) out[i] = Eval{}(in[i]);
}

/// Evaluates `Eval` on every case on the device.
template <typename Eval>
std::vector<typename Eval::Out> on_device(const std::vector<typename Eval::Case>& cases) {
    using Case = typename Eval::Case;
    using Out = typename Eval::Out;
    const auto n = static_cast<unsigned>(cases.size());
    auto in = device_alloc<Case>(n);
    auto out = device_alloc<Out>(n);
    check(cudaMemcpy(in.get(), cases.data(), n * sizeof(Case), cudaMemcpyHostToDevice), "cudaMemcpy to device");
    check(cudaMemset(out.get(), 0xff, n * sizeof(Out)), "cudaMemset");  // NaN-filled: unwritten output shows
    constexpr unsigned kBlock = 128;
    evaluate_kernel<Eval><<<(n + kBlock - 1) / kBlock, kBlock>>>(in.get(), out.get(), n);
    check(cudaGetLastError(), "kernel launch");
    check(cudaDeviceSynchronize(), "kernel execution");
    std::vector<Out> result(n);
    check(cudaMemcpy(result.data(), out.get(), n * sizeof(Out), cudaMemcpyDeviceToHost), "cudaMemcpy to host");
    return result;
}

/// The same evaluation on the host.
template <typename Eval>
std::vector<typename Eval::Out> on_host(const std::vector<typename Eval::Case>& cases) {
    std::vector<typename Eval::Out> result;
    result.reserve(cases.size());
    for (const auto& c : cases) result.push_back(Eval{}(c));
    return result;
}

// ---- comparing ------------------------------------------------------------------------------------

void append(std::vector<float>& out, V v) { out.insert(out.end(), {v.x, v.y, v.z}); }
void append(std::vector<float>& out, const M& m) {
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) out.push_back(m.m[r][c]);
}

/// Largest host-device difference of one quantity over all cases, relative to the quantity's magnitude.
class Tally {
public:
    explicit Tally(std::string name) : name_(std::move(name)) {}

    /// `scale_floor`: the magnitude below which the quantity counts as zero for this case (so a
    /// vanishing quantity is compared in absolute terms, not relative to its own rounding noise).
    void add(std::size_t index, const std::vector<float>& host, const std::vector<float>& device, double scale_floor) {
        double scale = scale_floor;
        for (float h : host) scale = std::max(scale, std::fabs(static_cast<double>(h)));
        for (std::size_t k = 0; k < host.size(); ++k) {
            const double err = std::fabs(static_cast<double>(host[k]) - static_cast<double>(device[k]));
            const double rel = err / scale;
            if (!(rel <= kRelTol)) {  // NaN (unwritten device output) fails too
                if (bad_ == 0)
                    first_bad_ = "case " + std::to_string(index) + " component " + std::to_string(k) + ": host " +
                                 std::to_string(host[k]) + ", device " + std::to_string(device[k]);
                ++bad_;
            }
            if (rel > max_rel_ || std::isnan(rel)) {
                max_rel_ = std::isnan(rel) ? INFINITY : rel;
                worst_ = index;
            }
            if (host[k] != device[k]) ++differing_;
            ++values_;
        }
    }

    /// Prints the largest error and fails the test if any value is out of tolerance.
    void report() const {
        std::printf("[ physics  ] %-34s max rel error %.2e (case %zu), %zu of %zu values not bit-identical\n",
                    name_.c_str(), max_rel_, worst_, differing_, values_);
        EXPECT_GT(values_, 0U) << name_;
        EXPECT_EQ(bad_, 0U) << name_ << ": " << bad_ << " values beyond " << kRelTol
                            << " relative; first: " << first_bad_;
    }

private:
    std::string name_;
    double max_rel_ = 0.0;
    std::size_t worst_ = 0, bad_ = 0, differing_ = 0, values_ = 0;
    std::string first_bad_;
};

// ---- random inputs --------------------------------------------------------------------------------

class Random {
public:
    explicit Random(unsigned seed) : rng_(seed) {}
    double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
    double sign() { return uniform(0.0, 1.0) < 0.5 ? -1.0 : 1.0; }
    Vec3<double> vec(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
    Vec3<double> unit() {
        for (;;) {
            const Vec3<double> v = vec(-1.0, 1.0);
            const double l = length(v);
            if (l > 0.1 && l <= 1.0) return v / l;
        }
    }
    /// A uniformly random rotation (from a random unit quaternion).
    Mat3<double> rotation() {
        double q[4];
        double l = 0.0;
        do {
            l = 0.0;
            for (double& c : q) {
                c = uniform(-1.0, 1.0);
                l += c * c;
            }
        } while (l < 0.01 || l > 1.0);
        l = std::sqrt(l);
        const double w = q[0] / l, x = q[1] / l, y = q[2] / l, z = q[3] / l;
        Mat3<double> r;
        // clang-format off
        r.m[0][0] = 1 - 2 * (y * y + z * z); r.m[0][1] = 2 * (x * y - w * z);     r.m[0][2] = 2 * (x * z + w * y);
        r.m[1][0] = 2 * (x * y + w * z);     r.m[1][1] = 1 - 2 * (x * x + z * z); r.m[1][2] = 2 * (y * z - w * x);
        r.m[2][0] = 2 * (x * z - w * y);     r.m[2][1] = 2 * (y * z + w * x);     r.m[2][2] = 1 - 2 * (x * x + y * y);
        // clang-format on
        return r;
    }

private:
    std::mt19937 rng_;
};

V to_float(Vec3<double> v) { return v.cast<float>(); }

constexpr HessianKind kKinds[] = {HessianKind::Fast, HessianKind::Projected, HessianKind::Exact};
const char* kind_name(HessianKind k) {
    switch (k) {
        case HessianKind::Fast:
            return "fast";
        case HessianKind::Projected:
            return "projected";
        case HessianKind::Exact:
            return "exact";
        default:
            return "none";
    }
}

// ---- membrane -------------------------------------------------------------------------------------

struct MembraneEval {
    struct Case {
        float dm_inv[2][2];
        float area;
        MembraneMaterial<float> material;
        V x[3];
        HessianKind kind;
    };
    struct Out {
        float energy;
        V grad[3];
        M hess[3][3];
    };
    __host__ __device__ Out operator()(const Case& c) const {
        Out o{};
        o.energy = membrane_evaluate(c.dm_inv, c.area, c.material, c.x, o.grad, o.hess, c.kind);
        return o;
    }
};

std::vector<MembraneEval::Case> membrane_cases(HessianKind kind) {
    Random r(101 + static_cast<unsigned>(kind));
    std::vector<MembraneEval::Case> cases;
    while (cases.size() < kCases) {
        MembraneEval::Case c{};
        // Rest triangle of cloth-cell size (1–5 cm) and a reasonable shape (area ≥ 0.2 of edge²).
        const double size = r.uniform(0.01, 0.05);
        const Vec3<double> X[3] = {
            {0, 0, 0}, {size, 0, 0}, {size * r.uniform(-0.3, 1.3), size * r.uniform(0.4, 1.2), 0}};
        V Xf[3];
        for (int a = 0; a < 3; ++a) Xf[a] = to_float(X[a]);
        if (!membrane_rest(Xf[0], Xf[1], Xf[2], c.dm_inv, c.area)) continue;
        c.material =
            membrane_material(static_cast<float>(r.uniform(1e3, 1e6)), static_cast<float>(r.uniform(0.0, 0.45)));
        // Deformed: stretched or compressed by up to 25% along random in-plane axes (both tension
        // and compression, so the Fast clamp and the projection are exercised), sheared, lifted
        // slightly out of plane, then rotated and placed up to 2 m away as in a scene.
        const double sx = r.uniform(0.8, 1.25), sy = r.uniform(0.8, 1.25), shear = r.uniform(-0.2, 0.2);
        const Mat3<double> rot = r.rotation();
        const Vec3<double> offset = r.vec(-2.0, 2.0);
        for (int a = 0; a < 3; ++a) {
            const Vec3<double> d{sx * X[a].x + shear * X[a].y, sy * X[a].y, size * r.uniform(-0.05, 0.05)};
            c.x[a] = to_float(rot * d + offset);
        }
        c.kind = kind;
        cases.push_back(c);
    }
    return cases;
}

TEST(PhysicsDevice, MembraneMatchesHost) {
    WEFT_REQUIRE_GPU();
    for (HessianKind kind : kKinds) {
        const auto cases = membrane_cases(kind);
        const auto host = on_host<MembraneEval>(cases);
        const auto dev = on_device<MembraneEval>(cases);
        const std::string k = kind_name(kind);
        Tally energy("membrane energy (" + k + ")"), grad("membrane gradient (" + k + ")"),
            hess("membrane Hessian (" + k + ")");
        for (std::size_t i = 0; i < cases.size(); ++i) {
            // Floors: the energy, force and stiffness of a 1% strain of this triangle; below them a
            // value counts as zero.
            const MembraneEval::Case& c = cases[i];
            const double k_area =
                static_cast<double>(c.area) * (static_cast<double>(c.material.mu) + c.material.lambda);
            const double edge = std::sqrt(static_cast<double>(c.area));
            energy.add(i, {host[i].energy}, {dev[i].energy}, 1e-4 * k_area);
            std::vector<float> gh, gd, hh, hd;
            for (int a = 0; a < 3; ++a) {
                append(gh, host[i].grad[a]);
                append(gd, dev[i].grad[a]);
                for (int b = 0; b < 3; ++b) {
                    append(hh, host[i].hess[a][b]);
                    append(hd, dev[i].hess[a][b]);
                }
            }
            grad.add(i, gh, gd, 1e-2 * k_area / edge);
            hess.add(i, hh, hd, k_area / (edge * edge));
        }
        energy.report();
        grad.report();
        hess.report();
    }
}

// ---- bending --------------------------------------------------------------------------------------

struct BendingEval {
    struct Case {
        float stiffness, weight, rest_angle;
        V x[4];
        HessianKind kind;
    };
    struct Out {
        float energy;
        float angle;
        V grad[4];
        M hess[4][4];
    };
    __host__ __device__ Out operator()(const Case& c) const {
        Out o{};
        o.energy = bending_evaluate(c.stiffness, c.weight, c.rest_angle, c.x, o.grad, o.hess, c.kind);
        o.angle = dihedral_angle(c.x);
        return o;
    }
};

std::vector<BendingEval::Case> bending_cases(HessianKind kind) {
    Random r(202 + static_cast<unsigned>(kind));
    std::vector<BendingEval::Case> cases;
    while (cases.size() < kCases) {
        BendingEval::Case c{};
        // Edge along x, wing 2 in the xy plane, wing 3 rotated about the edge by `fold` from flat.
        const double l = r.uniform(0.01, 0.05);
        const double h2 = l * r.uniform(0.5, 1.5), h3 = l * r.uniform(0.5, 1.5);
        const double fold = r.uniform(-2.6, 2.6);
        const Vec3<double> local[4] = {{0, 0, 0},
                                       {l, 0, 0},
                                       {l * r.uniform(0.1, 0.9), h2, 0},
                                       {l * r.uniform(0.1, 0.9), -h3 * std::cos(fold), -h3 * std::sin(fold)}};
        const Mat3<double> rot = r.rotation();
        const Vec3<double> offset = r.vec(-2.0, 2.0);
        Vec3<double> xd[4];
        for (int a = 0; a < 4; ++a) {
            xd[a] = rot * local[a] + offset;
            c.x[a] = to_float(xd[a]);
        }
        c.rest_angle = r.uniform(0.0, 1.0) < 0.3 ? 0.0F : static_cast<float>(r.uniform(-1.0, 1.0));
        // Keep θ − θ̄ at least 0.3 rad: the gradient is proportional to it, and a few ulps of atan2
        // in θ (≈ 1e-7 rad) must stay small relative to it. Keep θ away from the ±π branch cut.
        const double theta = dihedral_angle(xd);
        if (std::fabs(theta) > 2.8 || std::fabs(theta - c.rest_angle) < 0.3) continue;
        c.stiffness = static_cast<float>(r.uniform(1e-6, 1e-2));
        c.weight = static_cast<float>(r.uniform(0.5, 3.0));
        c.kind = kind;
        cases.push_back(c);
    }
    return cases;
}

TEST(PhysicsDevice, BendingMatchesHost) {
    WEFT_REQUIRE_GPU();
    for (HessianKind kind : kKinds) {
        const auto cases = bending_cases(kind);
        const auto host = on_host<BendingEval>(cases);
        const auto dev = on_device<BendingEval>(cases);
        const std::string k = kind_name(kind);
        Tally angle("dihedral angle"), energy("bending energy (" + k + ")"), grad("bending gradient (" + k + ")"),
            hess("bending Hessian (" + k + ")");
        for (std::size_t i = 0; i < cases.size(); ++i) {
            const BendingEval::Case& c = cases[i];
            const double kw = static_cast<double>(c.stiffness) * c.weight;
            const double l = static_cast<double>(length(c.x[1] - c.x[0]));
            angle.add(i, {host[i].angle}, {dev[i].angle}, 1.0);
            energy.add(i, {host[i].energy}, {dev[i].energy}, 1e-3 * kw);
            std::vector<float> gh, gd, hh, hd;
            for (int a = 0; a < 4; ++a) {
                append(gh, host[i].grad[a]);
                append(gd, dev[i].grad[a]);
                for (int b = 0; b < 4; ++b) {
                    append(hh, host[i].hess[a][b]);
                    append(hd, dev[i].hess[a][b]);
                }
            }
            grad.add(i, gh, gd, 1e-2 * kw / l);
            hess.add(i, hh, hd, kw / (l * l));
        }
        if (kind == HessianKind::Fast) angle.report();
        energy.report();
        grad.report();
        hess.report();
    }
}

// ---- collider contact -----------------------------------------------------------------------------

struct ContactEval {
    struct Case {
        Shape<float> shape;
        ContactParams<float> params;
        V x, v;
        HessianKind kind;
    };
    using Out = ContactResult<float>;
    __host__ __device__ Out operator()(const Case& c) const {
        return collider_contact(c.shape, c.params, c.x, c.v, c.kind);
    }
};

/// A point at signed distance `d` from `s` (exactly, up to rounding), placed where the surface is
/// smooth: faces of planes and boxes, away from box edges unless `d` > 0 puts it in an edge or
/// corner region on purpose, away from sphere centres and capsule axes (|d| ≪ radius).
Vec3<double> point_at_distance(Random& r, const Shape<double>& s, double d) {
    Vec3<double> local{};
    switch (s.kind) {
        case ShapeKind::Plane:
            local = {r.uniform(-1.0, 1.0), d, r.uniform(-1.0, 1.0)};
            break;
        case ShapeKind::Sphere:
            local = (s.radius + d) * r.unit();
            break;
        case ShapeKind::Capsule: {
            if (r.uniform(0.0, 1.0) < 0.7) {  // the cylinder
                const double a = r.uniform(0.0, 6.283185307179586);
                local = {(s.radius + d) * std::cos(a), r.uniform(-0.9, 0.9) * s.half_height,
                         (s.radius + d) * std::sin(a)};
            } else {  // a cap: directions that point away from the cylinder
                Vec3<double> dir = r.unit();
                const double end = r.sign();
                if (dir.y * end < 0.2) dir.y = end * (0.2 + std::fabs(dir.y));
                dir = dir / length(dir);
                local = Vec3<double>{0.0, end * s.half_height, 0.0} + (s.radius + d) * dir;
            }
            break;
        }
        case ShapeKind::Box: {
            const int axis = static_cast<int>(r.uniform(0.0, 3.0)) % 3;
            const double side = r.sign();
            if (d > 0.0 && r.uniform(0.0, 1.0) < 0.4) {
                // Outside an edge (two axes) or a corner (three): distance to the closest edge/corner point.
                Vec3<double> dir{};
                const int axes = r.uniform(0.0, 1.0) < 0.5 ? 2 : 3;
                for (int k = 0; k < 3; ++k) {
                    if (k == axis && axes == 2) continue;
                    dir[k] = r.sign() * r.uniform(0.3, 1.0);
                }
                dir = dir / length(dir);
                for (int k = 0; k < 3; ++k) {
                    const double h = s.half_extents[k];
                    local[k] = dir[k] == 0.0 ? r.uniform(-0.8, 0.8) * h : (dir[k] > 0 ? h : -h) + d * dir[k];
                }
            } else {  // a face: tangential coordinates well inside it, so this face is the nearest
                for (int k = 0; k < 3; ++k) local[k] = r.uniform(-0.8, 0.8) * s.half_extents[k];
                local[axis] = side * (s.half_extents[axis] + d);
            }
            break;
        }
    }
    return s.rotation * local + s.origin;
}

std::vector<ContactEval::Case> contact_cases(ShapeKind shape_kind, HessianKind kind) {
    Random r(303 + 7 * static_cast<unsigned>(shape_kind) + static_cast<unsigned>(kind));
    std::vector<ContactEval::Case> cases;
    while (cases.size() < kCases) {
        Shape<double> s{};
        s.kind = shape_kind;
        s.rotation = r.rotation();
        s.origin = r.vec(-1.0, 1.0);
        s.radius = r.uniform(0.1, 0.5);
        s.half_height = r.uniform(0.1, 1.0);
        s.half_extents = r.vec(0.1, 0.5);
        s.linear_velocity = r.vec(-1.0, 1.0);
        s.angular_velocity = r.vec(-2.0, 2.0);
        ContactEval::Case c{};
        c.params = {static_cast<float>(r.uniform(1e3, 1e5)), static_cast<float>(r.uniform(0.002, 0.01)),
                    r.uniform(0.0, 1.0) < 0.2 ? 0.0F : static_cast<float>(r.uniform(0.1, 0.8)), 0.01F};
        const double h = c.params.thickness;
        // Half inside the contact layer (penetration from 0.2 h to 2 h), half outside it (distance
        // 1.2 h to 5 h): never within 0.2 h of the threshold, where a rounding could flip `active`.
        const bool inside = cases.size() % 2 == 0;
        const double d = inside ? r.uniform(-1.0, 0.8) * h : r.uniform(1.2, 5.0) * h;
        c.x = to_float(point_at_distance(r, s, d));
        c.v = to_float(r.vec(-1.0, 1.0));
        c.shape.kind = s.kind;
        c.shape.rotation = s.rotation.cast<float>();
        c.shape.origin = to_float(s.origin);
        c.shape.radius = static_cast<float>(s.radius);
        c.shape.half_height = static_cast<float>(s.half_height);
        c.shape.half_extents = to_float(s.half_extents);
        c.shape.linear_velocity = to_float(s.linear_velocity);
        c.shape.angular_velocity = to_float(s.angular_velocity);
        c.kind = kind;
        cases.push_back(c);
    }
    return cases;
}

TEST(PhysicsDevice, ColliderContactMatchesHostForEveryShape) {
    WEFT_REQUIRE_GPU();
    const std::pair<ShapeKind, const char*> shapes[] = {{ShapeKind::Plane, "plane"},
                                                        {ShapeKind::Sphere, "sphere"},
                                                        {ShapeKind::Capsule, "capsule"},
                                                        {ShapeKind::Box, "box"}};
    for (const auto& [shape, shape_name] : shapes) {
        for (HessianKind kind : kKinds) {
            SCOPED_TRACE(shape_name);
            const auto cases = contact_cases(shape, kind);
            const auto host = on_host<ContactEval>(cases);
            const auto dev = on_device<ContactEval>(cases);
            const std::string n = std::string(shape_name) + ", " + kind_name(kind) + ")";
            Tally dist("contact distance (" + n), normal("contact normal (" + n), energy("contact energy (" + n),
                force("contact force (" + n), dfdx("contact dfdx (" + n), dfdv("contact dfdv (" + n);
            std::size_t active = 0, mismatched = 0;
            for (std::size_t i = 0; i < cases.size(); ++i) {
                const ContactEval::Case& c = cases[i];
                const ContactResult<float>& a = host[i];
                const ContactResult<float>& b = dev[i];
                if (a.active != b.active) {
                    ++mismatched;
                    continue;
                }
                active += a.active ? 1 : 0;
                // Floors: the contact thickness for lengths, and the force, energy and stiffness of a
                // penetration of one thickness; friction's ∂f/∂v is at most μ·f_n/ε.
                const double k = c.params.stiffness, h = c.params.thickness;
                dist.add(i, {a.distance}, {b.distance}, h);
                std::vector<float> nh, nd;
                append(nh, a.normal);
                append(nd, b.normal);
                normal.add(i, nh, nd, 1.0);
                energy.add(i, {a.energy, a.normal_force}, {b.energy, b.normal_force}, 0.5 * k * h * h);
                std::vector<float> fh, fd, xh, xd, vh, vd;
                append(fh, a.force);
                append(fd, b.force);
                append(xh, a.dfdx);
                append(xd, b.dfdx);
                append(vh, a.dfdv);
                append(vd, b.dfdv);
                force.add(i, fh, fd, k * h);
                dfdx.add(i, xh, xd, k);
                dfdv.add(i, vh, vd,
                         std::max(1e-6, static_cast<double>(c.params.friction) * k * h / c.params.slip_velocity));
            }
            EXPECT_EQ(mismatched, 0U) << "cases whose active flag differs between host and device";
            // The inputs were built half inside the contact layer: the host must agree (a check of the
            // test's own geometry).
            EXPECT_EQ(active, cases.size() / 2);
            for (const Tally* t : {&dist, &normal, &energy, &force, &dfdx, &dfdv}) t->report();
        }
    }
}

// ---- aerodynamics ---------------------------------------------------------------------------------

struct AeroEval {
    struct Case {
        V x[3], v[3], wind;
        AeroCoefficients<float> coefficients;
    };
    struct Out {
        V force;
        M damping;
    };
    __host__ __device__ Out operator()(const Case& c) const {
        Out o{};
        aerodynamic_force(c.x, c.v, c.wind, c.coefficients, o.force, &o.damping);
        return o;
    }
};

TEST(PhysicsDevice, AerodynamicForceMatchesHost) {
    WEFT_REQUIRE_GPU();
    Random r(404);
    std::vector<AeroEval::Case> cases;
    while (cases.size() < kCases) {
        AeroEval::Case c{};
        const double size = r.uniform(0.01, 0.05);
        const Mat3<double> rot = r.rotation();
        const Vec3<double> offset = r.vec(-2.0, 2.0);
        const Vec3<double> local[3] = {
            {0, 0, 0}, {size, 0, 0}, {size * r.uniform(-0.3, 1.3), size * r.uniform(0.4, 1.2), 0}};
        for (int a = 0; a < 3; ++a) c.x[a] = to_float(rot * local[a] + offset);
        const Vec3<double> base = r.vec(-2.0, 2.0);
        for (int a = 0; a < 3; ++a) c.v[a] = to_float(base + r.vec(-0.2, 0.2));
        c.wind = to_float(Vec3<double>{r.uniform(2.0, 12.0), r.uniform(-1.0, 1.0), r.uniform(-2.0, 2.0)});
        c.coefficients = {1.2F, static_cast<float>(r.uniform(0.5, 2.0)), static_cast<float>(r.uniform(0.0, 1.0))};
        cases.push_back(c);
    }
    const auto host = on_host<AeroEval>(cases);
    const auto dev = on_device<AeroEval>(cases);
    Tally force("aerodynamic force"), damping("aerodynamic damping matrix");
    for (std::size_t i = 0; i < cases.size(); ++i) {
        const AeroEval::Case& c = cases[i];
        // Floors: the broadside force ½ρ(C_D + C_L)A|u|² and its derivative ½ρ(C_D + C_L)A|u|, from which
        // the edge-on cases (u nearly in the plane, force nearly zero) are measured.
        const Vec3<double> u = ((c.v[0] + c.v[1] + c.v[2]) / 3.0F - c.wind).cast<double>();
        const double area = 0.5 * length(cross(c.x[1] - c.x[0], c.x[2] - c.x[0]).cast<double>());
        const double q = 0.5 * c.coefficients.air_density * area * (c.coefficients.drag + c.coefficients.lift);
        std::vector<float> fh, fd, dh, dd;
        append(fh, host[i].force);
        append(fd, dev[i].force);
        append(dh, host[i].damping);
        append(dd, dev[i].damping);
        force.add(i, fh, fd, 1e-2 * q * length_squared(u));
        damping.add(i, dh, dd, 1e-2 * q * length(u));
    }
    force.report();
    damping.report();
}

struct GustEval {
    struct Case {
        V p;
        float t, amplitude, frequency, scale;
    };
    using Out = V;
    __host__ __device__ Out operator()(const Case& c) const {
        return wind_gust(c.p, c.t, c.amplitude, c.frequency, c.scale);
    }
};

TEST(PhysicsDevice, WindGustMatchesHost) {
    WEFT_REQUIRE_GPU();
    Random r(505);
    std::vector<GustEval::Case> cases;
    while (cases.size() < kCases) {
        GustEval::Case c{};
        c.p = to_float(r.vec(-5.0, 5.0));
        c.t = static_cast<float>(r.uniform(0.0, 100.0));
        c.amplitude = static_cast<float>(r.uniform(0.5, 5.0));
        c.frequency = static_cast<float>(r.uniform(0.1, 3.0));
        c.scale = static_cast<float>(r.uniform(0.2, 3.0));
        cases.push_back(c);
    }
    const auto host = on_host<GustEval>(cases);
    const auto dev = on_device<GustEval>(cases);
    Tally gust("wind gust");
    for (std::size_t i = 0; i < cases.size(); ++i) {
        // The field's RMS speed is about `amplitude`: the floor below which a gust counts as calm.
        std::vector<float> h, d;
        append(h, host[i]);
        append(d, dev[i]);
        gust.add(i, h, d, 1e-2 * cases[i].amplitude);
    }
    gust.report();
}

}  // namespace
}  // namespace weft::physics
