#pragma once
// WEFT_VECTOR_CLONES: builds a hot CPU loop for AVX2 as well as for the baseline x86-64, the copy
// picked when the program loads (GCC/Clang target_clones, on x86-64 ELF; elsewhere one build). The
// project compiles with -ffp-contract=off and without -ffast-math, so both copies do the same
// operations in the same order: the same bits on every CPU.

#if defined(__x86_64__) && defined(__GNUC__) && defined(__ELF__)
#define WEFT_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define WEFT_VECTOR_CLONES
#endif
