// See bsr_rows.h.
#include "cpu/bsr_rows.h"

#include <cstring>

#include "cpu/vector_clones.h"

namespace weft::cpu {
namespace {

/// Four lanes of T (GCC/Clang vector extension): lanes 0–2 are the three rows of a block's product,
/// lane 3 is ignored. Each lane does what the scalar code does for its row, so the bits are the
/// same; the three rows just run side by side instead of one after the other (the scalar loop was
/// 30 instructions a block).
template <typename T>
struct LanesOf;
template <>
struct LanesOf<float> {
    using type = float __attribute__((vector_size(4 * sizeof(float))));
};
template <>
struct LanesOf<double> {
    using type = double __attribute__((vector_size(4 * sizeof(double))));
};
template <typename T>
using Lanes = typename LanesOf<T>::type;

static_assert(sizeof(physics::Mat3<float>) == 9 * sizeof(float) && sizeof(physics::Mat3<double>) == 9 * sizeof(double),
              "the column loads step through Mat3 blocks as plain arrays of scalars");

/// The lanes at p, unaligned; the 4th reads the next column (or the padding block).
template <typename T>
inline void load_lanes(const T* p, Lanes<T>& lanes) {
    std::memcpy(&lanes, p, sizeof lanes);
}

/// acc += block × x as lanes: lane r adds (m_r0·x + m_r1·y) + m_r2·z, the order of Mat3 × Vec3.
/// (Vectors pass by reference: a 4-double vector by value would change the ABI between the clones.)
template <typename T>
inline void add_block_times(const physics::Mat3<T>& columns, physics::Vec3<T> x, Lanes<T>& acc) {
    const T* c = &columns.m[0][0];
    Lanes<T> c0, c1, c2;
    load_lanes(c, c0);
    load_lanes(c + 3, c1);
    load_lanes(c + 6, c2);
    acc += c0 * x.x + c1 * x.y + c2 * x.z;
}

template <typename T>
inline physics::Vec3<T> row_times(const physics::Mat3<T>* columns, const std::uint32_t* row_start, const std::uint32_t* column,
                                  const physics::Vec3<T>* x, std::size_t i) {
    Lanes<T> acc{};
    for (std::uint32_t s = row_start[i]; s < row_start[i + 1]; ++s) add_block_times(columns[s], x[column[s]], acc);
    return {acc[0], acc[1], acc[2]};
}

template <typename T>
inline void rows_times(const physics::Mat3<T>* columns, const std::uint32_t* row_start, const std::uint32_t* column,
                       const physics::Vec3<T>* x, physics::Vec3<T>* y, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) y[i] = row_times(columns, row_start, column, x, i);
}

template <typename T>
inline double rows_times_dot(const physics::Mat3<T>* columns, const std::uint32_t* row_start, const std::uint32_t* column,
                             const physics::Vec3<T>* x, physics::Vec3<T>* y, const std::uint8_t* fixed, std::size_t begin,
                             std::size_t end) {
    double acc = 0.0;
    for (std::size_t i = begin; i < end; ++i) {
        const physics::Vec3<T> row = fixed[i] ? physics::Vec3<T>{} : row_times(columns, row_start, column, x, i);
        y[i] = row;
        acc += static_cast<double>(physics::dot(x[i], row));
    }
    return acc;
}

}  // namespace

WEFT_VECTOR_CLONES void bsr_rows_times(const physics::Mat3<double>* columns, const std::uint32_t* row_start,
                                       const std::uint32_t* column, const physics::Vec3<double>* x,
                                       physics::Vec3<double>* y, std::size_t begin, std::size_t end) {
    rows_times(columns, row_start, column, x, y, begin, end);
}

WEFT_VECTOR_CLONES void bsr_rows_times(const physics::Mat3<float>* columns, const std::uint32_t* row_start,
                                       const std::uint32_t* column, const physics::Vec3<float>* x, physics::Vec3<float>* y,
                                       std::size_t begin, std::size_t end) {
    rows_times(columns, row_start, column, x, y, begin, end);
}

WEFT_VECTOR_CLONES double bsr_rows_times_dot(const physics::Mat3<double>* columns, const std::uint32_t* row_start,
                                             const std::uint32_t* column, const physics::Vec3<double>* x,
                                             physics::Vec3<double>* y, const std::uint8_t* fixed, std::size_t begin,
                                             std::size_t end) {
    return rows_times_dot(columns, row_start, column, x, y, fixed, begin, end);
}

WEFT_VECTOR_CLONES double bsr_rows_times_dot(const physics::Mat3<float>* columns, const std::uint32_t* row_start,
                                             const std::uint32_t* column, const physics::Vec3<float>* x,
                                             physics::Vec3<float>* y, const std::uint8_t* fixed, std::size_t begin,
                                             std::size_t end) {
    return rows_times_dot(columns, row_start, column, x, y, fixed, begin, end);
}

}  // namespace weft::cpu
