// See pcg_rows.h.
#include "cpu/pcg_rows.h"

#include "cpu/vector_clones.h"

namespace weft::cpu {
namespace {

template <typename T>
inline double update_rows(physics::Vec3<T>* dv, physics::Vec3<T>* r, const physics::Vec3<T>* q, const physics::Vec3<T>* c,
                          physics::Vec3<T>* s, const physics::Mat3<T>* inverse_diagonal, T alpha, std::size_t begin,
                          std::size_t end) {
    double acc = 0.0;
    for (std::size_t i = begin; i < end; ++i) {
        dv[i] += alpha * c[i];
        r[i] -= alpha * q[i];
        s[i] = inverse_diagonal[i] * r[i];
        acc += static_cast<double>(physics::dot(r[i], s[i]));
    }
    return acc;
}

template <typename T>
inline void next_direction_rows(physics::Vec3<T>* c, const physics::Vec3<T>* s, const std::uint8_t* fixed, T beta,
                                std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) c[i] = fixed[i] ? physics::Vec3<T>{} : s[i] + beta * c[i];
}

}  // namespace

WEFT_VECTOR_CLONES double pcg_jacobi_update_rows(physics::Vec3<double>* dv, physics::Vec3<double>* r,
                                                 const physics::Vec3<double>* q, const physics::Vec3<double>* c,
                                                 physics::Vec3<double>* s, const physics::Mat3<double>* inverse_diagonal,
                                                 double alpha, std::size_t begin, std::size_t end) {
    return update_rows(dv, r, q, c, s, inverse_diagonal, alpha, begin, end);
}

WEFT_VECTOR_CLONES double pcg_jacobi_update_rows(physics::Vec3<float>* dv, physics::Vec3<float>* r,
                                                 const physics::Vec3<float>* q, const physics::Vec3<float>* c,
                                                 physics::Vec3<float>* s, const physics::Mat3<float>* inverse_diagonal,
                                                 float alpha, std::size_t begin, std::size_t end) {
    return update_rows(dv, r, q, c, s, inverse_diagonal, alpha, begin, end);
}

WEFT_VECTOR_CLONES void pcg_next_direction_rows(physics::Vec3<double>* c, const physics::Vec3<double>* s,
                                                const std::uint8_t* fixed, double beta, std::size_t begin, std::size_t end) {
    next_direction_rows(c, s, fixed, beta, begin, end);
}

WEFT_VECTOR_CLONES void pcg_next_direction_rows(physics::Vec3<float>* c, const physics::Vec3<float>* s,
                                                const std::uint8_t* fixed, float beta, std::size_t begin, std::size_t end) {
    next_direction_rows(c, s, fixed, beta, begin, end);
}

}  // namespace weft::cpu
