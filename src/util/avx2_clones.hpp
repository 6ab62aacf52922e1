#pragma once
// Compiling a hot kernel twice, for AVX2 and for the baseline, with the variant picked at
// load time (GCC's target_clones, an ifunc: x86-64 with glibc). AVX2 without FMA does the
// same operations in the same order as the baseline, so the same bits, provided the file
// is built with -ffp-contract=off (CMakeLists.txt). Elsewhere the kernel is compiled once.
// Private to src/.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FREEFLEX_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FREEFLEX_AVX2_CLONES
#endif

// Inlined into each clone, so that the clone's instructions reach the helper's loops too.
#if defined(__GNUC__)
#define FREEFLEX_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define FREEFLEX_ALWAYS_INLINE inline
#endif
