#include "../../core/simd_x86.h"
#include "lane_gather.h"

#include "path_kernels.h"
#include "../../render/interaction.h"

#include <cstddef>
#include <utility>

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
        col[WiZ * st] = dot(-src.rays[path[m]].d, si.sh_frame.n); // to_local(-d).z
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

void gather_nee_scalar(float *cols, size_t st, size_t n, const uint32_t *path, const uint32_t *vertex,
                       const LaneSources &src) {
    using namespace ln_col;
    for (size_t m = 0; m < n; ++m) {
        const SurfaceInteraction &si = src.si[path[m]];
        const Spectrum &beta = src.paths[path[m]].throughput;
        const ScatterVertex &v = src.scatter[vertex[m]];
        const LightSample &ls = v.emitter_sample.first;
        const Spectrum &weight = v.emitter_sample.second;
        float *const col = cols + m;
        col[WiZ * st] = dot(-src.rays[path[m]].d, si.sh_frame.n); // to_local(-d).z
        col[Nx * st] = si.sh_frame.n.x, col[Ny * st] = si.sh_frame.n.y, col[Nz * st] = si.sh_frame.n.z;
        col[Px * st] = si.p.x, col[Py * st] = si.p.y, col[Pz * st] = si.p.z;
        col[Gx * st] = si.n.x, col[Gy * st] = si.n.y, col[Gz * st] = si.n.z;
        col[Rr * st] = v.refl.r, col[Rg * st] = v.refl.g, col[Rb * st] = v.refl.b;
        col[Br * st] = beta.r, col[Bg * st] = beta.g, col[Bb * st] = beta.b;
        col[Ldx * st] = ls.d.x, col[Ldy * st] = ls.d.y, col[Ldz * st] = ls.d.z;
        col[Lpx * st] = ls.p.x, col[Lpy * st] = ls.p.y, col[Lpz * st] = ls.p.z;
        col[LDist * st] = ls.dist, col[LPdf * st] = ls.pdf, col[LDelta * st] = ls.delta ? 1.f : 0.f;
        col[Wr * st] = weight.r, col[Wg * st] = weight.g, col[Wb * st] = weight.b;
    }
}

#if MVPT_X86_SIMD
/// A 16-lane step of lanes [m, n): its mask, the lanes' scattering vertices and their
/// records' first words.
struct Step {
    __mmask16 lanes;
    __m512i k, j, at_si, at_path, at_vertex;
};

[[gnu::target("avx512f"), gnu::always_inline]] inline Step step_at(size_t m, size_t n, const uint32_t *path,
                                                                  const uint32_t *vertex) {
    Step s;
    s.lanes = n - m >= 16 ? __mmask16(0xffff) : __mmask16((1u << (n - m)) - 1);
    s.k = _mm512_maskz_loadu_epi32(s.lanes, path + m);
    s.j = _mm512_maskz_loadu_epi32(s.lanes, vertex + m);
    s.at_si = _mm512_mullo_epi32(s.k, _mm512_set1_epi32(int(word(sizeof(SurfaceInteraction)))));
    s.at_path = _mm512_mullo_epi32(s.k, _mm512_set1_epi32(int(word(sizeof(WavePath)))));
    s.at_vertex = _mm512_mullo_epi32(s.j, _mm512_set1_epi32(int(word(sizeof(ScatterVertex)))));
    return s;
}

/// The step's lanes of column `col` from the words at `base` + index.
[[gnu::target("avx512f"), gnu::always_inline]] inline void gather_column(float *col, __mmask16 lanes, __m512i index,
                                                                        const float *base) {
    _mm512_mask_storeu_ps(col, lanes, _mm512_mask_i32gather_ps(_mm512_setzero_ps(), lanes, index, base, sizeof(float)));
}

/// The step's WiZ column: -ray.d in the shading frame, its z (Frame::to_local's dot(v, n),
/// in its order of operations; the sign flipped exactly), from the lanes' rays and the
/// shading normals at `normal` (+0..2).
[[gnu::target("avx512f"), gnu::always_inline]] inline void wi_z_column(float *col, const Step &s, const Ray *rays,
                                                                      const float *normal) {
    static_assert(sizeof(Ray) == 9 * sizeof(float));
    const float *const d = &rays[0].d.x;
    const __m512i at_ray = _mm512_mullo_epi32(s.k, _mm512_set1_epi32(int(word(sizeof(Ray)))));
    const __m512i sign = _mm512_set1_epi32(int(0x80000000u));
    __m512 sum = _mm512_setzero_ps();
    for (int q = 0; q < 3; ++q) {
        const __m512 dq = _mm512_mask_i32gather_ps(_mm512_setzero_ps(), s.lanes, at_ray, d + q, sizeof(float));
        const __m512 vq = _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(dq), sign));
        const __m512 nq = _mm512_mask_i32gather_ps(_mm512_setzero_ps(), s.lanes, s.at_si, normal + q, sizeof(float));
        const __m512 term = _mm512_mul_ps(vq, nq);
        sum = q == 0 ? term : _mm512_add_ps(sum, term);
    }
    _mm512_mask_storeu_ps(col, s.lanes, sum);
}

/// gather_scalar, 16 lanes per step: one index vector per record kind, one gather per column.
[[gnu::target("avx512f")]] void gather_avx512(float *cols, size_t st, size_t n, const uint32_t *path,
                                               const uint32_t *vertex, const LaneSources &src, bool light_numbers) {
    using namespace lam_col;
    const float *const si = reinterpret_cast<const float *>(src.si);
    const float *const wp = reinterpret_cast<const float *>(src.paths);
    const float *const sv = reinterpret_cast<const float *>(src.scatter);
    const __m512i rr_depth = _mm512_set1_epi32(int(src.rr_depth)), one = _mm512_set1_epi32(1);
    for (size_t m = 0; m < n; m += 16) {
        const Step s = step_at(m, n, path, vertex);
        const __mmask16 lanes = s.lanes;
        auto column = [&](size_t c) { return cols + c * st + m; };
        wi_z_column(column(WiZ), s, src.rays,
                    si + word(offsetof(SurfaceInteraction, sh_frame) + offsetof(Frame, n)));
        for (size_t q = 0; q < 9; ++q)
            gather_column(column(Sx + q), lanes, s.at_si, si + word(offsetof(SurfaceInteraction, sh_frame)) + q);
        for (size_t q = 0; q < 3; ++q) {
            gather_column(column(Px + q), lanes, s.at_si, si + word(offsetof(SurfaceInteraction, p)) + q);
            gather_column(column(Gx + q), lanes, s.at_si, si + word(offsetof(SurfaceInteraction, n)) + q);
            gather_column(column(Rr + q), lanes, s.at_vertex, sv + word(offsetof(ScatterVertex, refl)) + q);
            gather_column(column(Br + q), lanes, s.at_path, wp + word(offsetof(WavePath, throughput)) + q);
        }
        gather_column(column(Eta), lanes, s.at_path, wp + word(offsetof(WavePath, eta)));
        gather_column(column(URr), lanes, s.j, src.u[6]);
        gather_column(column(DirUx), lanes, s.j, src.u[4]);
        gather_column(column(DirUy), lanes, s.j, src.u[5]);
        if (light_numbers) {
            gather_column(column(LightUx), lanes, s.j, src.u[1]);
            gather_column(column(LightUy), lanes, s.j, src.u[2]);
        }
        const __m512i depth = _mm512_mask_i32gather_epi32(_mm512_setzero_si512(), lanes, s.at_path,
                                                          wp + word(offsetof(WavePath, depth)), sizeof(uint32_t));
        const __mmask16 rr_on = _mm512_cmpge_epu32_mask(_mm512_add_epi32(depth, one), rr_depth);
        _mm512_mask_storeu_ps(cols + RrOn * st + m, lanes, _mm512_maskz_mov_ps(rr_on, _mm512_set1_ps(1.f)));
    }
}

/// gather_nee_scalar, 16 lanes per step.
[[gnu::target("avx512f")]] void gather_nee_avx512(float *cols, size_t st, size_t n, const uint32_t *path,
                                                   const uint32_t *vertex, const LaneSources &src) {
    using namespace ln_col;
    using Sample = std::pair<LightSample, Spectrum>;
    static_assert(sizeof(bool) == 1 && offsetof(LightSample, delta) % 4 == 0, "the delta flag is a word's low byte");
    const float *const si = reinterpret_cast<const float *>(src.si);
    const float *const wp = reinterpret_cast<const float *>(src.paths);
    const float *const sv = reinterpret_cast<const float *>(src.scatter);
    const float *const es = sv + word(offsetof(ScatterVertex, emitter_sample));
    const float *const ls = es + word(offsetof(Sample, first)), *const weight = es + word(offsetof(Sample, second));
    for (size_t m = 0; m < n; m += 16) {
        const Step s = step_at(m, n, path, vertex);
        const __mmask16 lanes = s.lanes;
        auto column = [&](size_t c) { return cols + c * st + m; };
        const float *const normal = si + word(offsetof(SurfaceInteraction, sh_frame) + offsetof(Frame, n));
        wi_z_column(column(WiZ), s, src.rays, normal);
        for (size_t q = 0; q < 3; ++q) {
            gather_column(column(Nx + q), lanes, s.at_si, normal + q);
            gather_column(column(Px + q), lanes, s.at_si, si + word(offsetof(SurfaceInteraction, p)) + q);
            gather_column(column(Gx + q), lanes, s.at_si, si + word(offsetof(SurfaceInteraction, n)) + q);
            gather_column(column(Rr + q), lanes, s.at_vertex, sv + word(offsetof(ScatterVertex, refl)) + q);
            gather_column(column(Br + q), lanes, s.at_path, wp + word(offsetof(WavePath, throughput)) + q);
            gather_column(column(Ldx + q), lanes, s.at_vertex, ls + word(offsetof(LightSample, d)) + q);
            gather_column(column(Lpx + q), lanes, s.at_vertex, ls + word(offsetof(LightSample, p)) + q);
            gather_column(column(Wr + q), lanes, s.at_vertex, weight + q);
        }
        gather_column(column(LDist), lanes, s.at_vertex, ls + word(offsetof(LightSample, dist)));
        gather_column(column(LPdf), lanes, s.at_vertex, ls + word(offsetof(LightSample, pdf)));
        const __m512i delta = _mm512_mask_i32gather_epi32(_mm512_setzero_si512(), lanes, s.at_vertex,
                                                          ls + word(offsetof(LightSample, delta)), sizeof(uint32_t));
        const __mmask16 is_delta = _mm512_test_epi32_mask(delta, _mm512_set1_epi32(0xff));
        _mm512_mask_storeu_ps(cols + LDelta * st + m, lanes, _mm512_maskz_mov_ps(is_delta, _mm512_set1_ps(1.f)));
    }
}

/// append_shadow_rays, 16 lanes per step: each column compressed to the lanes that count.
[[gnu::target("avx512f")]] size_t append_avx512(const float *cols, size_t st, size_t n, size_t o0,
                                                 const uint32_t *path, const SurfaceInteraction *si,
                                                 float *const shadow[8], PendingShadow *pending, size_t ns) {
    static_assert(sizeof(PendingShadow) == 4 * sizeof(float) && offsetof(PendingShadow, contribution) == sizeof(float));
    const float *const time = reinterpret_cast<const float *>(si) + word(offsetof(SurfaceInteraction, time));
    const __m512i si_words = _mm512_set1_epi32(int(word(sizeof(SurfaceInteraction))));
    for (size_t m = 0; m < n; m += 16) {
        const __mmask16 lanes = n - m >= 16 ? __mmask16(0xffff) : __mmask16((1u << (n - m)) - 1);
        // !(ok > 0), as the scalar loop: a NaN does not count.
        const __mmask16 ok =
            _mm512_mask_cmp_ps_mask(lanes, _mm512_maskz_loadu_ps(lanes, cols + (o0 + 10) * st + m), _mm512_setzero_ps(),
                                    _CMP_GT_OQ);
        if (ok == 0) continue;
        for (size_t q = 0; q < 7; ++q)
            _mm512_storeu_ps(shadow[q] + ns, _mm512_maskz_compress_ps(ok, _mm512_maskz_loadu_ps(ok, cols + (o0 + q) * st + m)));
        const __m512i k = _mm512_maskz_compress_epi32(ok, _mm512_maskz_loadu_epi32(ok, path + m));
        const unsigned count = unsigned(__builtin_popcount(ok));
        const __mmask16 first = __mmask16((1u << count) - 1);
        _mm512_storeu_ps(shadow[7] + ns, _mm512_mask_i32gather_ps(_mm512_setzero_ps(), first,
                                                                  _mm512_mullo_epi32(k, si_words), time, sizeof(float)));
        // The records {path, r, g, b} of the compressed lanes: a 4 x 16 transpose.
        const __m512 kf = _mm512_castsi512_ps(k);
        const __m512 r = _mm512_maskz_compress_ps(ok, _mm512_maskz_loadu_ps(ok, cols + (o0 + 7) * st + m));
        const __m512 g = _mm512_maskz_compress_ps(ok, _mm512_maskz_loadu_ps(ok, cols + (o0 + 8) * st + m));
        const __m512 b = _mm512_maskz_compress_ps(ok, _mm512_maskz_loadu_ps(ok, cols + (o0 + 9) * st + m));
        const __m512 t0 = _mm512_unpacklo_ps(kf, r), t1 = _mm512_unpacklo_ps(g, b);
        const __m512 t2 = _mm512_unpackhi_ps(kf, r), t3 = _mm512_unpackhi_ps(g, b);
        // Record 4i + c of each 128-bit block i: oc's block i.
        const __m512 o0r = _mm512_shuffle_ps(t0, t1, 0x44), o1r = _mm512_shuffle_ps(t0, t1, 0xee);
        const __m512 o2r = _mm512_shuffle_ps(t2, t3, 0x44), o3r = _mm512_shuffle_ps(t2, t3, 0xee);
        const __m512 u0 = _mm512_shuffle_f32x4(o0r, o1r, 0x44), u1 = _mm512_shuffle_f32x4(o2r, o3r, 0x44);
        const __m512 u2 = _mm512_shuffle_f32x4(o0r, o1r, 0xee), u3 = _mm512_shuffle_f32x4(o2r, o3r, 0xee);
        float *const out = reinterpret_cast<float *>(pending + ns);
        _mm512_storeu_ps(out, _mm512_shuffle_f32x4(u0, u1, 0x88));
        _mm512_storeu_ps(out + 16, _mm512_shuffle_f32x4(u0, u1, 0xdd));
        _mm512_storeu_ps(out + 32, _mm512_shuffle_f32x4(u2, u3, 0x88));
        _mm512_storeu_ps(out + 48, _mm512_shuffle_f32x4(u2, u3, 0xdd));
        ns += count;
    }
    return ns;
}

#endif

size_t append_scalar(const float *cols, size_t st, size_t n, size_t o0, const uint32_t *path,
                     const SurfaceInteraction *si, float *const shadow[8], PendingShadow *pending, size_t ns) {
    for (size_t m = 0; m < n; ++m) {
        auto at = [cols, st, m](size_t c) { return cols[c * st + m]; };
        if (!(at(o0 + 10) > 0.f)) continue;
        for (size_t q = 0; q < 7; ++q) shadow[q][ns] = at(o0 + q);
        shadow[7][ns] = si[path[m]].time;
        pending[ns++] = {path[m], Spectrum(at(o0 + 7), at(o0 + 8), at(o0 + 9))};
    }
    return ns;
}

} // namespace

size_t append_shadow_rays(const float *cols, size_t stride, size_t n, size_t o0, const uint32_t *path,
                          const SurfaceInteraction *si, float *const shadow[8], PendingShadow *pending, size_t count,
                          bool vector) {
#if MVPT_X86_SIMD
    if (vector && cpu_has_avx512f()) return append_avx512(cols, stride, n, o0, path, si, shadow, pending, count);
#endif
    return append_scalar(cols, stride, n, o0, path, si, shadow, pending, count);
}

void gather_lambert_nee_lanes(float *cols, size_t stride, size_t n, const uint32_t *path, const uint32_t *vertex,
                              const LaneSources &src, bool vector) {
#if MVPT_X86_SIMD
    if (vector && cpu_has_avx512f()) return gather_nee_avx512(cols, stride, n, path, vertex, src);
#endif
    gather_nee_scalar(cols, stride, n, path, vertex, src);
}

void gather_lambert_lanes(float *cols, size_t stride, size_t n, const uint32_t *path, const uint32_t *vertex,
                          const LaneSources &src, bool light_numbers, bool vector) {
#if MVPT_X86_SIMD
    if (vector && cpu_has_avx512f()) return gather_avx512(cols, stride, n, path, vertex, src, light_numbers);
#endif
    gather_scalar(cols, stride, n, path, vertex, src, light_numbers);
}

} // namespace mvpt
