// The vector idiom of mvpt's loops over views, segments and samples: fixed-width vectors of
// the GCC vector extension (GCC and Clang), and functions compiled once per x86-64
// instruction-set level (AVX-512, AVX2, baseline) and picked when the library loads
// (MVPT_MULTI_ISA). The build turns off FMA contraction, so every clone rounds exactly like
// the baseline one and images do not depend on the CPU. The word gathers and compresses that
// need AVX-512's instructions are the only intrinsics, in core/simd_gather.cpp.
#pragma once

#include <cstdint>
#include <cstring>

#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define MVPT_MULTI_ISA __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define MVPT_MULTI_ISA
#endif

// The helpers below (and those of the files using these types) take and return vectors and
// are always inlined, so the baseline clone's vector ABI, which GCC warns about, never applies.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace mvpt::simd {

typedef float f32x4 __attribute__((vector_size(16)));
typedef float f32x8 __attribute__((vector_size(32)));
typedef double f64x4 __attribute__((vector_size(32)));
typedef int32_t i32x4 __attribute__((vector_size(16)));
typedef int32_t i32x8 __attribute__((vector_size(32)));
typedef int64_t i64x4 __attribute__((vector_size(32)));
typedef uint64_t u64x8 __attribute__((vector_size(64)));

/// A vector from sizeof(V) bytes at p (any alignment).
template <class V> [[gnu::always_inline]] inline V load(const void *p) {
    V v;
    std::memcpy(&v, p, sizeof(v));
    return v;
}
/// The bytes of v to p (any alignment).
template <class V> [[gnu::always_inline]] inline void store(void *p, const V &v) { std::memcpy(p, &v, sizeof(v)); }
/// The same bits as another vector type of the same size.
template <class To, class From> [[gnu::always_inline]] inline To bit_cast(const From &v) {
    static_assert(sizeof(To) == sizeof(From));
    To t;
    std::memcpy(&t, &v, sizeof(t));
    return t;
}

} // namespace mvpt::simd
