#include "../core/simd_x86.h"
#include "ray_packet.h"

#include <algorithm>
#include <cstddef>

namespace mvpt {

namespace {

#if MVPT_X86_SIMD
[[gnu::target("avx512f")]] void pack_avx512(const Ray *rays, uint32_t m, RTCRay16 &p, int *valid) {
    static_assert(sizeof(Ray) == 9 * sizeof(float) && offsetof(Ray, tmin) == 6 * sizeof(float) &&
                  offsetof(Ray, tmax) == 7 * sizeof(float));
    const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    const __m512i index = _mm512_mullo_epi32(_mm512_min_epu32(lane, _mm512_set1_epi32(int(m - 1))), _mm512_set1_epi32(9));
    const float *const base = &rays[0].o.x;
    float *const field[8] = {p.org_x, p.org_y, p.org_z, p.dir_x, p.dir_y, p.dir_z, p.tnear, p.tfar};
    const __m512 large = _mm512_set1_ps(1.844e18f);
    __mmask16 ok = _mm512_cmplt_epu32_mask(lane, _mm512_set1_epi32(int(m)));
    for (int f = 0; f < 8; ++f) {
        const __m512 v = _mm512_i32gather_ps(index, base + f, sizeof(float));
        _mm512_storeu_ps(field[f], v);
        // |coordinate| <= large for origin and direction, no NaN in the range (a NaN fails both).
        ok &= f < 6 ? _mm512_cmp_ps_mask(_mm512_abs_ps(v), large, _CMP_LE_OQ) : _mm512_cmp_ps_mask(v, v, _CMP_EQ_OQ);
    }
    _mm512_storeu_si512(valid, _mm512_maskz_set1_epi32(ok, -1));
}
#endif

} // namespace

void pack_ray16(const Ray *rays, uint32_t m, RTCRay16 &p, int *valid, bool vector) {
#if MVPT_X86_SIMD
    if (vector && cpu_has_avx512f()) {
        pack_avx512(rays, m, p, valid);
        return deactivate_invalid(p, valid);
    }
#endif
    for (uint32_t i = 0; i < 16; ++i) {
        const Ray &ray = rays[std::min(i, m - 1)];
        p.org_x[i] = ray.o.x, p.org_y[i] = ray.o.y, p.org_z[i] = ray.o.z;
        p.dir_x[i] = ray.d.x, p.dir_y[i] = ray.d.y, p.dir_z[i] = ray.d.z;
        p.tnear[i] = ray.tmin;
        p.tfar[i] = ray.tmax;
    }
    packet_valid(p, m, valid);
}

} // namespace mvpt
