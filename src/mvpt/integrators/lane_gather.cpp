#include "lane_gather.h"

#include "path_kernels.h"
#include "../render/interaction.h"

#include <cstddef>
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

namespace mvpt {

namespace {

// The records' fields as float (or uint32) word offsets: the AVX-512 loop gathers words.
static_assert(sizeof(SurfaceInteraction) % 4 == 0 && sizeof(WavePath) % 4 == 0 && sizeof(ScatterVertex) % 4 == 0);
static_assert(sizeof(Frame) == 9 * sizeof(float) && sizeof(Vec3f) == 3 * sizeof(float) &&
              sizeof(Color3f) == 3 * sizeof(float));
constexpr size_t word(size_t bytes) { return bytes / sizeof(float); }

void gather_scalar(float *cols, size_t st, size_t n, const uint32_t *path, const uint32_t *vertex,
                   const LaneSources &src, bool light_numbers) {
    using namespace lam_col;
    for (size_t m = 0; m < n; ++m) {
        const SurfaceInteraction &si = src.si[path[m]];
        const WavePath &p = src.paths[path[m]];
        const uint32_t j = vertex[m];
        float *const col = cols + m;
        col[WiZ * st] = si.wi.z;
        const Frame &f = si.sh_frame;
        const float frame[9] = {f.s.x, f.s.y, f.s.z, f.t.x, f.t.y, f.t.z, f.n.x, f.n.y, f.n.z};
        for (size_t q = 0; q < 9; ++q) col[(Sx + q) * st] = frame[q];
        col[Px * st] = si.p.x, col[Py * st] = si.p.y, col[Pz * st] = si.p.z;
        col[Gx * st] = si.n.x, col[Gy * st] = si.n.y, col[Gz * st] = si.n.z;
        const Color3f &refl = src.scatter[j].refl;
        col[Rr * st] = refl.r, col[Rg * st] = refl.g, col[Rb * st] = refl.b;
        col[Br * st] = p.throughput.r, col[Bg * st] = p.throughput.g, col[Bb * st] = p.throughput.b;
        col[Eta * st] = p.eta, col[URr * st] = src.u[6][j];
        col[RrOn * st] = p.depth + 1 >= src.rr_depth ? 1.f : 0.f;
        col[DirUx * st] = src.u[4][j], col[DirUy * st] = src.u[5][j];
        if (light_numbers) col[LightUx * st] = src.u[1][j], col[LightUy * st] = src.u[2][j];
    }
}

#if defined(__GNUC__) && defined(__x86_64__)
/// gather_scalar, 16 lanes per step: one index vector per record kind, one gather per column.
[[gnu::target("avx512f")]] void gather_avx512(float *cols, size_t st, size_t n, const uint32_t *path,
                                               const uint32_t *vertex, const LaneSources &src, bool light_numbers) {
    using namespace lam_col;
    const float *const si = reinterpret_cast<const float *>(src.si);
    const float *const wp = reinterpret_cast<const float *>(src.paths);
    const float *const sv = reinterpret_cast<const float *>(src.scatter);
    const __m512i si_words = _mm512_set1_epi32(int(word(sizeof(SurfaceInteraction))));
    const __m512i path_words = _mm512_set1_epi32(int(word(sizeof(WavePath))));
    const __m512i vertex_words = _mm512_set1_epi32(int(word(sizeof(ScatterVertex))));
    const __m512i rr_depth = _mm512_set1_epi32(int(src.rr_depth)), one = _mm512_set1_epi32(1);
    for (size_t m = 0; m < n; m += 16) {
        const __mmask16 lanes = n - m >= 16 ? __mmask16(0xffff) : __mmask16((1u << (n - m)) - 1);
        const __m512i k = _mm512_maskz_loadu_epi32(lanes, path + m), j = _mm512_maskz_loadu_epi32(lanes, vertex + m);
        const __m512i at_si = _mm512_mullo_epi32(k, si_words), at_path = _mm512_mullo_epi32(k, path_words),
                      at_vertex = _mm512_mullo_epi32(j, vertex_words);
        // Column `c` from the words at `base` + index (a macro: a lambda would not inherit the target).
#define MVPT_GATHER(c, index, base)                                                                                \
    _mm512_mask_storeu_ps(cols + (c) * st + m, lanes,                                                              \
                          _mm512_mask_i32gather_ps(_mm512_setzero_ps(), lanes, index, base, sizeof(float)))
        MVPT_GATHER(WiZ, at_si, si + word(offsetof(SurfaceInteraction, wi)) + 2);
        for (size_t q = 0; q < 9; ++q) MVPT_GATHER(Sx + q, at_si, si + word(offsetof(SurfaceInteraction, sh_frame)) + q);
        for (size_t q = 0; q < 3; ++q) MVPT_GATHER(Px + q, at_si, si + word(offsetof(SurfaceInteraction, p)) + q);
        for (size_t q = 0; q < 3; ++q) MVPT_GATHER(Gx + q, at_si, si + word(offsetof(SurfaceInteraction, n)) + q);
        for (size_t q = 0; q < 3; ++q) MVPT_GATHER(Rr + q, at_vertex, sv + word(offsetof(ScatterVertex, refl)) + q);
        for (size_t q = 0; q < 3; ++q) MVPT_GATHER(Br + q, at_path, wp + word(offsetof(WavePath, throughput)) + q);
        MVPT_GATHER(Eta, at_path, wp + word(offsetof(WavePath, eta)));
        MVPT_GATHER(URr, j, src.u[6]);
        MVPT_GATHER(DirUx, j, src.u[4]);
        MVPT_GATHER(DirUy, j, src.u[5]);
        if (light_numbers) {
            MVPT_GATHER(LightUx, j, src.u[1]);
            MVPT_GATHER(LightUy, j, src.u[2]);
        }
#undef MVPT_GATHER
        const __m512i depth = _mm512_mask_i32gather_epi32(_mm512_setzero_si512(), lanes, at_path,
                                                          wp + word(offsetof(WavePath, depth)), sizeof(uint32_t));
        const __mmask16 rr_on = _mm512_cmpge_epu32_mask(_mm512_add_epi32(depth, one), rr_depth);
        _mm512_mask_storeu_ps(cols + RrOn * st + m, lanes, _mm512_maskz_mov_ps(rr_on, _mm512_set1_ps(1.f)));
    }
}

bool has_avx512f() {
    static const bool yes = __builtin_cpu_supports("avx512f");
    return yes;
}
#endif

} // namespace

void gather_lambert_lanes(float *cols, size_t stride, size_t n, const uint32_t *path, const uint32_t *vertex,
                          const LaneSources &src, bool light_numbers, bool vector) {
#if defined(__GNUC__) && defined(__x86_64__)
    if (vector && has_avx512f()) return gather_avx512(cols, stride, n, path, vertex, src, light_numbers);
#endif
    gather_scalar(cols, stride, n, path, vertex, src, light_numbers);
}

} // namespace mvpt
