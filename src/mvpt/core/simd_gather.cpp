#include "simd_gather.h"

// The AVX-512 loops of simd::gather and simd::compress, compiled with a target attribute and
// picked at run time. A test compiles this file once more against portable stand-ins of the
// intrinsics (MVPT_SIMD_EMULATED, tests/cpp/test_simd_gather.cpp), so that they run on any CPU.
#if defined(MVPT_SIMD_EMULATED)
#define MVPT_AVX512 1
#define MVPT_AVX512_FN inline
#define MVPT_AVX512_FN_EXTERN
#define MVPT_SIMD_NAMESPACE mvpt::simd::emulated
#elif defined(__GNUC__) && defined(__x86_64__)
#define MVPT_AVX512 1
#define MVPT_AVX512_FN [[gnu::target("avx512f")]] inline
#define MVPT_AVX512_FN_EXTERN [[gnu::target("avx512f")]]
#define MVPT_SIMD_NAMESPACE mvpt::simd
// GCC 12's AVX-512 headers start masked and gathered results from an "undefined" vector that
// -Wuninitialized reports (GCC bug 105593); every lane it leaves is masked off.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <immintrin.h>
#pragma GCC diagnostic pop
#else
#define MVPT_AVX512 0
#define MVPT_SIMD_NAMESPACE mvpt::simd
#endif

namespace MVPT_SIMD_NAMESPACE {

#if MVPT_AVX512
namespace {

/// The lanes [m, n) of a 16-lane step.
MVPT_AVX512_FN __mmask16 step_lanes(size_t m, size_t n) {
    return n - m >= 16 ? __mmask16(0xffff) : __mmask16((1u << (n - m)) - 1);
}

} // namespace

/// simd::gather's loop, 16 lanes per step: one index vector, then one gather per field. A whole
/// step is one vector store, which later vector loads forward from.
MVPT_AVX512_FN_EXTERN void gather_avx512(void *cols, size_t stride, size_t n, const uint32_t *index,
                                         const void *records, size_t record_bytes, std::span<const Field> fields) {
    const char *const base = static_cast<const char *>(records);
    const __m512i words = _mm512_set1_epi32(int(record_bytes / sizeof(float)));
    for (size_t m = 0; m < n; m += 16) {
        const __mmask16 lanes = step_lanes(m, n);
        const __m512i at = _mm512_mullo_epi32(_mm512_maskz_loadu_epi32(lanes, index + m), words);
        for (const Field &f : fields) {
            const __m512 v = _mm512_mask_i32gather_ps(_mm512_setzero_ps(), lanes, at, base + f.offset, sizeof(float));
            float *const column = static_cast<float *>(cols) + f.column * stride + m;
            if (lanes == 0xffff)
                _mm512_storeu_ps(column, v);
            else
                _mm512_mask_storeu_ps(column, lanes, v);
        }
    }
}

/// simd::compress's loop, 16 lanes per step: one compress and one whole-vector store per column.
MVPT_AVX512_FN_EXTERN size_t compress_avx512(const void *const *in, void *const *out, size_t columns,
                                             const float *keep, size_t n) {
    size_t count = 0;
    for (size_t m = 0; m < n; m += 16) {
        const __mmask16 lanes = step_lanes(m, n);
        // keep > 0, ordered: a NaN does not count.
        const __mmask16 ok =
            _mm512_mask_cmp_ps_mask(lanes, _mm512_maskz_loadu_ps(lanes, keep + m), _mm512_setzero_ps(), _CMP_GT_OQ);
        if (ok == 0) continue;
        for (size_t c = 0; c < columns; ++c) {
            const __m512 v = _mm512_maskz_loadu_ps(ok, static_cast<const float *>(in[c]) + m);
            _mm512_storeu_ps(static_cast<float *>(out[c]) + count, _mm512_maskz_compress_ps(ok, v));
        }
        count += size_t(__builtin_popcount(ok));
    }
    return count;
}
#else
// Never called: cpu_has_avx512f() is false on other CPUs.
void gather_avx512(void *, size_t, size_t, const uint32_t *, const void *, size_t, std::span<const Field>) {}
size_t compress_avx512(const void *const *, void *const *, size_t, const float *, size_t) { return 0; }
#endif

} // namespace MVPT_SIMD_NAMESPACE
