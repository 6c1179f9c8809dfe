/* The build's vector switches, shared by the nodes' vector code (coherent noise maps its own
 * names onto them in internal_coherent_noise.h), never installed.
 *
 * GCC/Clang vector extensions express vector code (INTERNAL_SIMD); on x86-64 Linux with GCC a
 * hot function marked INTERNAL_SIMD_CLONES is also built for AVX2 and AVX-512 and picked at load
 * time. Vector and scalar paths must do the same IEEE operations in the same order (the project
 * builds with -ffp-contract=off), so that every path, CPU and thread count gives the same
 * numbers. NPRFX_SCALAR builds the scalar paths only. */
#ifndef NPRFX_INTERNAL_SIMD_H
#define NPRFX_INTERNAL_SIMD_H

#if !defined(NPRFX_SCALAR) &&                                                                      \
    ((defined(__GNUC__) && __GNUC__ >= 12) || (defined(__clang__) && __clang_major__ >= 13))
#define INTERNAL_SIMD 1
#else
#define INTERNAL_SIMD 0
#endif

/* GCC or Clang on x86-64: hot loops may have target("avx2") copies, picked at run time with
 * __builtin_cpu_supports (stipple, the IVS index scan). */
#if defined(__GNUC__) && defined(__x86_64__) && defined(__SSE2__)
#define INTERNAL_X86 1
#else
#define INTERNAL_X86 0
#endif

#if INTERNAL_SIMD && defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) &&            \
    defined(__linux__) && !defined(NPRFX_NO_CLONES)
#define INTERNAL_SIMD_CLONES                                                                       \
    __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define INTERNAL_SIMD_CLONES
#endif

#if INTERNAL_SIMD
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wpsabi"
#elif defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
/* Vector helpers are always inlined: no vector type crosses a call (no ABI question). */
#define INTERNAL_SIMD_INLINE static inline __attribute__((always_inline))
#endif

#endif
