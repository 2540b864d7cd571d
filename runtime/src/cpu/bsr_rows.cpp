// See bsr_rows.h.
#include "cpu/bsr_rows.h"

#include "cpu/vector_clones.h"

namespace weft::cpu {
namespace {

template <typename T>
inline void rows_times(const physics::Mat3<T>* blocks, const std::uint32_t* row_start, const std::uint32_t* column,
                       const physics::Vec3<T>* x, physics::Vec3<T>* y, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
        physics::Vec3<T> acc{};
        for (std::uint32_t s = row_start[i]; s < row_start[i + 1]; ++s) acc += blocks[s] * x[column[s]];
        y[i] = acc;
    }
}

template <typename T>
inline double rows_times_dot(const physics::Mat3<T>* blocks, const std::uint32_t* row_start, const std::uint32_t* column,
                             const physics::Vec3<T>* x, physics::Vec3<T>* y, const std::uint8_t* fixed, std::size_t begin,
                             std::size_t end) {
    double acc = 0.0;
    for (std::size_t i = begin; i < end; ++i) {
        physics::Vec3<T> row{};
        if (!fixed[i])
            for (std::uint32_t s = row_start[i]; s < row_start[i + 1]; ++s) row += blocks[s] * x[column[s]];
        y[i] = row;
        acc += static_cast<double>(physics::dot(x[i], row));
    }
    return acc;
}

}  // namespace

WEFT_VECTOR_CLONES void bsr_rows_times(const physics::Mat3<double>* blocks, const std::uint32_t* row_start,
                                       const std::uint32_t* column, const physics::Vec3<double>* x,
                                       physics::Vec3<double>* y, std::size_t begin, std::size_t end) {
    rows_times(blocks, row_start, column, x, y, begin, end);
}

WEFT_VECTOR_CLONES void bsr_rows_times(const physics::Mat3<float>* blocks, const std::uint32_t* row_start,
                                       const std::uint32_t* column, const physics::Vec3<float>* x, physics::Vec3<float>* y,
                                       std::size_t begin, std::size_t end) {
    rows_times(blocks, row_start, column, x, y, begin, end);
}

WEFT_VECTOR_CLONES double bsr_rows_times_dot(const physics::Mat3<double>* blocks, const std::uint32_t* row_start,
                                             const std::uint32_t* column, const physics::Vec3<double>* x,
                                             physics::Vec3<double>* y, const std::uint8_t* fixed, std::size_t begin,
                                             std::size_t end) {
    return rows_times_dot(blocks, row_start, column, x, y, fixed, begin, end);
}

WEFT_VECTOR_CLONES double bsr_rows_times_dot(const physics::Mat3<float>* blocks, const std::uint32_t* row_start,
                                             const std::uint32_t* column, const physics::Vec3<float>* x,
                                             physics::Vec3<float>* y, const std::uint8_t* fixed, std::size_t begin,
                                             std::size_t end) {
    return rows_times_dot(blocks, row_start, column, x, y, fixed, begin, end);
}

}  // namespace weft::cpu
