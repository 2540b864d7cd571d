#pragma once
// An allocator for std::vector whose storage starts on a cache line, for the CPU backend's dense
// arrays that its AVX2 loops read and write a whole row at a time (cpu/schwarz_preconditioner.h).

#include <cstddef>
#include <new>

namespace weft::cpu {

/// Allocates on `Alignment`-byte boundaries (a power of two, at least alignof(T)). Large blocks from
/// malloc start 16 bytes past a page, so every other 32-byte access of a row crossed a cache line.
template <typename T, std::size_t Alignment = 64>
struct AlignedAllocator {
    using value_type = T;
    static_assert(Alignment >= alignof(T) && (Alignment & (Alignment - 1)) == 0, "alignment must be a power of two");

    AlignedAllocator() noexcept = default;
    template <typename U>
    AlignedAllocator(const AlignedAllocator<U, Alignment>&) noexcept {}  // NOLINT(google-explicit-constructor)
    template <typename U>
    struct rebind {
        using other = AlignedAllocator<U, Alignment>;
    };

    [[nodiscard]] T* allocate(std::size_t n) {
        return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(Alignment)));
    }
    // The unsized form: the sized aligned delete is not declared where sized deallocation is off
    // (clang without -fsized-deallocation, the fuzz preset).
    void deallocate(T* p, std::size_t /*n*/) noexcept { ::operator delete(p, std::align_val_t(Alignment)); }

    template <typename U>
    bool operator==(const AlignedAllocator<U, Alignment>&) const noexcept {
        return true;
    }
};

}  // namespace weft::cpu
