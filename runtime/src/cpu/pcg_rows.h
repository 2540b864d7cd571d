#pragma once
// Rows of the block-Jacobi CG's vector passes (cpu/pcg.h), out of line so that they are built for
// AVX2 as well (cpu/vector_clones.h): the same expressions in the same order as written in the CG.

#include <cstddef>
#include <cstdint>

#include "weft/physics/vec.h"

namespace weft::cpu {

/// Rows [begin, end): dv += α·c, r −= α·q, s = P⁻¹·r (P⁻¹ the inverted diagonal blocks); returns
/// Σ rᵢ·sᵢ over the rows in row order, in double.
double pcg_jacobi_update_rows(physics::Vec3<double>* dv, physics::Vec3<double>* r, const physics::Vec3<double>* q,
                              const physics::Vec3<double>* c, physics::Vec3<double>* s,
                              const physics::Mat3<double>* inverse_diagonal, double alpha, std::size_t begin,
                              std::size_t end);
double pcg_jacobi_update_rows(physics::Vec3<float>* dv, physics::Vec3<float>* r, const physics::Vec3<float>* q,
                              const physics::Vec3<float>* c, physics::Vec3<float>* s,
                              const physics::Mat3<float>* inverse_diagonal, float alpha, std::size_t begin, std::size_t end);

/// Rows [begin, end): c = s + β·c, or 0 where fixed[i] != 0.
void pcg_next_direction_rows(physics::Vec3<double>* c, const physics::Vec3<double>* s, const std::uint8_t* fixed,
                             double beta, std::size_t begin, std::size_t end);
void pcg_next_direction_rows(physics::Vec3<float>* c, const physics::Vec3<float>* s, const std::uint8_t* fixed, float beta,
                             std::size_t begin, std::size_t end);

}  // namespace weft::cpu
