#include "mv_mixture.h"

#include <algorithm>

namespace mvpt {

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
        float p = 0.f;
        for (size_t c = 0; c < n; ++c) p += pdf_buf[c];
        ms.pdf = p / float(n);
    } else {
        ms.pdf = lobe_mixture_pdf(bsdf, si, wi, n, bs.wo);
    }
    return ms;
}

} // namespace mvpt
