#include "mv_mixture.h"

#include "../../core/simd.h"

#include <algorithm>

namespace mvpt {

namespace {
/// Eight running values, lane q taking the entries q, q + 8, ... (the order of the scalar loops).
using F8 = simd::f32x8;
[[gnu::always_inline]] inline F8 load8(const float *v) { return simd::load<F8>(v); }
} // namespace

MVPT_MULTI_ISA float sum_over_views(const float *v, size_t n) {
    F8 acc = {};
    size_t i = 0;
    for (; i + 8 <= n; i += 8) acc += load8(v + i);
    for (size_t q = 0; i + q < n; ++q) acc[q] += v[i + q];
    return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

MVPT_MULTI_ISA float max_over_views(const Spectrum *f, size_t n) {
    static_assert(sizeof(Spectrum) == 3 * sizeof(float));
    const float *v = &f[0].r; // the channels of all views as one array
    F8 acc = {};
    size_t i = 0;
    for (; i + 8 <= 3 * n; i += 8) {
        const F8 x = load8(v + i);
        acc = acc > x ? acc : x; // MAXPS: the scalar loop's choice, lane by lane
    }
    for (size_t q = 0; i + q < 3 * n; ++q) acc[q] = acc[q] > v[i + q] ? acc[q] : v[i + q];
    float m = 0.f;
    for (int q = 0; q < 8; ++q) m = m > acc[q] ? m : acc[q];
    return m;
}

float lobe_mixture_pdf(const Bsdf &bsdf, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo) {
    const BsdfContext ctx;
    float p = 0.f;
    for (size_t c = 0; c < n; ++c) p += bsdf.pdf(ctx, si, wi[c], wo);
    return n ? p / float(n) : 0.f;
}

MixtureSample sample_lobe_mixture(const Bsdf &bsdf, const SurfaceInteraction &si, const Vec3f *wi, size_t n,
                                  float u_view, float u_lobe, Vec2f u_dir, Spectrum *f, float *pdf_buf) {
    MixtureSample ms;
    if (n == 0) return ms;
    ms.view = std::min(size_t(u_view * float(n)), n - 1);
    auto [bs, weight] = bsdf.sample(BsdfContext{}, si, wi[ms.view], u_lobe, u_dir);
    ms.bs = bs;
    ms.weight = weight;
    if (weight.is_black()) return ms;
    ms.delta = (bs.sampled_type & BsdfDelta) != 0;
    if (ms.delta) {
        ms.pdf = bs.pdf / float(n);
    } else if (f && pdf_buf) {
        bsdf.eval_pdf_views(BsdfContext{}, si, wi, n, bs.wo, f, pdf_buf);
        ms.pdf = sum_over_views(pdf_buf, n) / float(n);
    } else {
        ms.pdf = lobe_mixture_pdf(bsdf, si, wi, n, bs.wo);
    }
    return ms;
}

} // namespace mvpt
