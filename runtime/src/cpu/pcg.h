#pragma once
// Modified preconditioned conjugate gradient with filtered constraints (Baraff & Witkin 1998 §5.3;
// the P-Cloth slide "Recalling CG Solver"). Pinned vertices have S = 0: their Δv is the prescribed
// z and never changes. Preconditioner: block-Jacobi (P⁻¹ = inverse of each 3×3 diagonal block), or
// the multilevel additive Schwarz one (cpu/schwarz_preconditioner.h) when the caller hands one over.
// Both stop on the preconditioned norm rᵀP⁻¹r relative to filter(b)ᵀP⁻¹filter(b) (docs/architecture.md,
// step 4): the norm the iteration minimises, so the test costs nothing extra; it differs between
// the two preconditioners, which is why docs/results.md also reports the plain residual. Past that
// test the loop may go on while the incremental potential still falls (weft/backend/cg_energy_stop.h).

#include <cmath>
#include <cstdint>
#include <vector>

#include "cpu/bsr_matrix.h"
#include "cpu/pcg_rows.h"
#include "cpu/schwarz_preconditioner.h"
#include "deterministic_parallel.h"
#include "weft/backend/cg_energy_stop.h"

namespace weft::cpu {

struct PcgResult {
    int iterations = 0;
    double relative_residual = 0.0;  ///< sqrt(δ_new / δ₀) at exit
    bool converged = false;
    /// Schwarz only: rᵀM⁻¹r came out negative (or NaN) for a nonzero r, so the preconditioner is not
    /// SPD in this precision (a domain matrix factored past a non-positive pivot) and the norm the
    /// loop stops on means nothing: the solve stops, not converged, and says so (the CPU solver then
    /// solves again with block-Jacobi). Before, such a solve stopped at once and reported convergence.
    bool preconditioner_failed = false;
};

template <typename T>
class Pcg {
public:
    using V3 = physics::Vec3<T>;
    using M3 = physics::Mat3<T>;

    void resize(std::size_t n) {
        r_.assign(n, V3{});
        c_.assign(n, V3{});
        q_.assign(n, V3{});
        s_.assign(n, V3{});
        precond_.assign(n, M3{});
    }

    /// The second stopping test's floor, J (cg_energy_floor; 0, the default, turns it off): past the
    /// residual test, the solves go on while the incremental potential fell by more than this over the
    /// last kCgEnergyDelay iterations, up to the iteration cap.
    void set_energy_floor(double joules) { energy_floor_ = joules; }

    /// Solves A·dv = b. On entry dv holds z (the prescribed values on filtered vertices, zero
    /// elsewhere); `fixed[i]` != 0 filters vertex i out completely. `A` is any symmetric operator
    /// with `multiply(x, y)` (y = A·x) and `diagonal_block(i)`: the fabric's BSR matrix alone, or the
    /// fabric plus the substep's contact springs (cpu_solver.cpp).
    /// With `schwarz` (factored for this A), the solve uses it instead of block-Jacobi.
    template <typename Operator>
    PcgResult solve(const Operator& A, const std::vector<V3>& b, const std::vector<std::uint8_t>& fixed,
                    std::vector<V3>& dv, double tolerance, int max_iterations,
                    SchwarzPreconditioner<T>* schwarz = nullptr) {
        if (schwarz != nullptr) return solve_schwarz(A, b, fixed, dv, tolerance, max_iterations, *schwarz);
        const std::size_t n = b.size();
        // Block-Jacobi preconditioner. Diagonal blocks are SPD (mass + PSD stiffness), so invertible.
        parallel_chunks(n, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i) precond_[i] = physics::inverse(A.diagonal_block(i));
        });
        // δ₀ = filter(b)ᵀ P⁻¹ filter(b): the scale the residual is measured against.
        const double delta0_b = sum(n, [&](std::size_t i) {
            return fixed[i] ? 0.0 : static_cast<double>(physics::dot(b[i], precond_[i] * b[i]));
        });
        // r = filter(b − A·dv); c = filter(P⁻¹ r); δ = rᵀc
        A.multiply(dv, q_);
        double delta = sum(n, [&](std::size_t i) {
            if (fixed[i]) {
                r_[i] = c_[i] = V3{};
                return 0.0;
            }
            r_[i] = b[i] - q_[i];
            c_[i] = precond_[i] * r_[i];
            return static_cast<double>(physics::dot(r_[i], c_[i]));
        });
        // Measure against the larger of |b| and the initial residual, so a solve whose right-hand side
        // vanishes but whose pinned values drive the rest still converges relative to something.
        const double delta0 = std::max(delta0_b, delta);
        PcgResult result;
        const double eps2 = tolerance * tolerance;
        if (!(delta0 > 0.0)) {  // nothing to do (or NaN: reported by the caller's finite check)
            result.converged = delta0 == 0.0;
            return result;
        }
        CgEnergyWindow window;
        window.reset();
        while (result.iterations < max_iterations && (delta > eps2 * delta0 || window.still_falling(energy_floor_))) {
            const double cq = product_along_direction(A, fixed);
            if (!(cq > 0.0)) break;  // loss of positive definiteness or breakdown: report, don't loop
            const T alpha = static_cast<T>(delta / cq);
            window.record(delta / cq, delta);
            // dv += α·c, r −= α·q, s = P⁻¹·r and δ' = rᵀs in one pass (cpu/pcg_rows.h).
            const double delta_new = deterministic_sum(n, partials_, [&](std::size_t lo, std::size_t hi) {
                return pcg_jacobi_update_rows(dv.data(), r_.data(), q_.data(), c_.data(), s_.data(), precond_.data(), alpha,
                                              lo, hi);
            });
            const T beta = static_cast<T>(delta_new / delta);
            delta = delta_new;
            next_direction(beta, fixed);
            ++result.iterations;
        }
        result.relative_residual = std::sqrt(std::max(delta, 0.0) / delta0);
        result.converged = delta <= eps2 * delta0;
        return result;
    }

    /// The same iteration with z = filter(M⁻¹ filter(r)) from the Schwarz preconditioner: the
    /// preconditioner is a whole-vector operation, so the fused per-row passes are split around it.
    template <typename Operator>
    PcgResult solve_schwarz(const Operator& A, const std::vector<V3>& b, const std::vector<std::uint8_t>& fixed,
                            std::vector<V3>& dv, double tolerance, int max_iterations, SchwarzPreconditioner<T>& M) {
        const std::size_t n = b.size();
        const auto precondition = [&](const std::vector<V3>& in, std::vector<V3>& out) {
            M.apply(in, out);
            parallel_chunks(n, [&](std::size_t lo, std::size_t hi) {
                for (std::size_t i = lo; i < hi; ++i)
                    if (fixed[i]) out[i] = V3{};
            });
        };
        parallel_chunks(n, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i) r_[i] = fixed[i] ? V3{} : b[i];
        });
        precondition(r_, s_);
        const double delta0_b = sum(n, [&](std::size_t i) { return static_cast<double>(physics::dot(r_[i], s_[i])); });
        A.multiply(dv, q_);
        parallel_chunks(n, [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i) r_[i] = fixed[i] ? V3{} : b[i] - q_[i];
        });
        precondition(r_, c_);
        double delta = sum(n, [&](std::size_t i) { return static_cast<double>(physics::dot(r_[i], c_[i])); });
        const double delta0 = std::max(delta0_b, delta);
        PcgResult result;
        const double eps2 = tolerance * tolerance;
        if (!(delta0 > 0.0)) {
            // rᵀM⁻¹r ≤ 0 (or NaN) with r ≠ 0: M is not SPD.
            result.preconditioner_failed =
                sum(n, [&](std::size_t i) { return static_cast<double>(physics::dot(r_[i], r_[i])); }) > 0.0;
            result.converged = delta0 == 0.0 && !result.preconditioner_failed;
            return result;
        }
        CgEnergyWindow window;
        window.reset();
        while (result.iterations < max_iterations && (delta > eps2 * delta0 || window.still_falling(energy_floor_))) {
            const double cq = product_along_direction(A, fixed);
            if (!(cq > 0.0)) break;
            const T alpha = static_cast<T>(delta / cq);
            window.record(delta / cq, delta);
            parallel_chunks(n, [&](std::size_t lo, std::size_t hi) {
                for (std::size_t i = lo; i < hi; ++i) {
                    dv[i] += alpha * c_[i];
                    r_[i] -= alpha * q_[i];
                }
            });
            precondition(r_, s_);
            const double delta_new = sum(n, [&](std::size_t i) { return static_cast<double>(physics::dot(r_[i], s_[i])); });
            if (delta_new < 0.0) {  // rᵀM⁻¹r < 0: M is not SPD
                result.preconditioner_failed = true;
                ++result.iterations;
                break;
            }
            const T beta = static_cast<T>(delta_new / delta);
            delta = delta_new;
            next_direction(beta, fixed);
            ++result.iterations;
        }
        result.relative_residual = std::sqrt(std::max(delta, 0.0) / delta0);
        result.converged = delta <= eps2 * delta0;
        if (result.preconditioner_failed) result.converged = false;
        return result;
    }

    [[nodiscard]] std::size_t memory_bytes() const {
        return (r_.capacity() + c_.capacity() + q_.capacity() + s_.capacity()) * sizeof(V3) +
               precond_.capacity() * sizeof(M3) + partials_.capacity() * sizeof(double);
    }

private:
    /// q = filter(A·c); returns cᵀq (the step length's denominator).
    template <typename Operator>
    double product_along_direction(const Operator& A, const std::vector<std::uint8_t>& fixed) {
        // One pass where the operator can fuse the product and the dot (the same bits either way).
        if constexpr (requires { A.multiply_dot(c_, q_, fixed, partials_); }) return A.multiply_dot(c_, q_, fixed, partials_);
        A.multiply(c_, q_);
        return sum(c_.size(), [&](std::size_t i) {
            if (fixed[i]) q_[i] = V3{};
            return static_cast<double>(physics::dot(c_[i], q_[i]));
        });
    }

    /// c = filter(s + β·c): the next search direction from the preconditioned residual s.
    void next_direction(T beta, const std::vector<std::uint8_t>& fixed) {
        parallel_chunks(c_.size(), [&](std::size_t lo, std::size_t hi) {
            pcg_next_direction_rows(c_.data(), s_.data(), fixed.data(), beta, lo, hi);
        });
    }

    template <typename F>
    double sum(std::size_t n, F&& per_row) {
        return deterministic_sum(n, partials_, [&](std::size_t lo, std::size_t hi) {
            double acc = 0.0;
            for (std::size_t i = lo; i < hi; ++i) acc += per_row(i);
            return acc;
        });
    }
    std::vector<V3> r_, c_, q_, s_;
    std::vector<M3> precond_;
    std::vector<double> partials_;
    double energy_floor_ = 0.0;  // J; set_energy_floor
};

}  // namespace weft::cpu
