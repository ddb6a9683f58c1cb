#include "mv_mixture.h"

#include "../../core/simd.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace mvpt {

namespace {
/// Eight running values, lane q taking the entries q, q + 8, ... (the order of the scalar loops).
using F8 = simd::f32x8;
/// The exponent of |S| in the odds of a delta event (§7, "Delta lobes"; docs/performance.md).
constexpr float DeltaOddsExponent = 0.375f;
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

LobeClasses lobe_classes(const Bsdf &bsdf, const SurfaceInteraction &si, const Vec3f *wi, size_t n, float *p_delta,
                         float *smooth_scale) {
    LobeClasses classes;
    if (n < 2 || !(bsdf.flags() & BsdfDelta) || !bsdf.has_smooth()) return classes;
    float sum = 0.f;
    for (size_t c = 0; c < n; ++c) {
        const std::optional<float> p = bsdf.delta_probability(si, wi[c]);
        if (!p) return classes;
        p_delta[c] = std::clamp(*p, 0.f, 1.f);
        sum += p_delta[c];
    }
    const float mean = sum / float(n);
    if (!(mean > 0.f)) return classes; // no view draws a delta lobe here: the plain mixture
    classes.split = true;
    classes.q = 1.f;
    if (mean < 1.f) {
        const float odds = std::pow(float(n), DeltaOddsExponent) * mean / (1.f - mean); // |S|^(3/8) P / (1 - P)
        classes.q = odds / (1.f + odds);
    }
    for (size_t c = 0; c < n; ++c)
        smooth_scale[c] = p_delta[c] < 1.f ? (1.f - classes.q) / (float(n) * (1.f - p_delta[c])) : 0.f;
    classes.p_delta = p_delta;
    classes.smooth_scale = smooth_scale;
    return classes;
}

float smooth_mixture_pdf(const LobeClasses &classes, const float *pdf, size_t n) {
    if (n == 0) return 0.f;
    if (!classes.split) return sum_over_views(pdf, n) / float(n);
    float p = 0.f;
    for (size_t c = 0; c < n; ++c) p += pdf[c] * classes.smooth_scale[c];
    return p;
}

float lobe_mixture_pdf(const Bsdf &bsdf, const SurfaceInteraction &si, const Vec3f *wi, size_t n,
                       const LobeClasses &classes, Vec3f wo) {
    const BsdfContext ctx;
    std::vector<float> pdf(n);
    for (size_t c = 0; c < n; ++c) pdf[c] = bsdf.pdf(ctx, si, wi[c], wo);
    return smooth_mixture_pdf(classes, pdf.data(), n);
}

MixtureSample sample_lobe_mixture(const Bsdf &bsdf, const SurfaceInteraction &si, const Vec3f *wi, size_t n,
                                  const LobeClasses &classes, float u_view, float u_lobe, Vec2f u_dir, Spectrum *f,
                                  float *pdf_buf) {
    MixtureSample ms;
    if (n == 0) return ms;
    // With split classes (§7, "Delta lobes") u_view first draws the kind, a delta event with
    // probability q, and what is left of it the view, whose lobe is then drawn conditioned on the
    // kind: one number for both, so that splits stratified in it take each kind and view in turn.
    BsdfContext ctx;
    float u = u_view, p_delta_event = 1.f;
    bool delta_event = false;
    if (classes.split) {
        const float q = classes.q;
        delta_event = u_view < q;
        u = std::min(delta_event ? u_view / q : (u_view - q) / (1.f - q), OneMinusEpsilon);
        p_delta_event = q;
    }
    ms.view = std::min(size_t(u * float(n)), n - 1);
    if (classes.split) {
        const float p_kind = delta_event ? classes.p_delta[ms.view] : 1.f - classes.p_delta[ms.view];
        if (!(p_kind > 0.f)) return ms; // this view has no lobe of the kind
        ctx.type_mask = delta_event ? uint32_t(BsdfDelta) : uint32_t(BsdfSmooth);
    }
    auto [bs, weight] = bsdf.sample(ctx, si, wi[ms.view], u_lobe, u_dir);
    ms.bs = bs;
    const bool delta = (bs.sampled_type & BsdfDelta) != 0;
    if (weight.is_black() || (classes.split && delta != delta_event)) return ms; // (zero weight: no direction)
    ms.delta = delta;
    if (ms.delta) { // the view's delta event, 1/n of q (1 unsplit), times the lobe's probability within it
        ms.pdf = p_delta_event * bs.pdf / float(n);
        ms.weight = weight * (1.f / p_delta_event);
    } else if (f && pdf_buf) {
        ms.weight = weight;
        bsdf.eval_pdf_views(BsdfContext{}, si, wi, n, bs.wo, f, pdf_buf);
        ms.pdf = smooth_mixture_pdf(classes, pdf_buf, n);
    } else {
        ms.weight = weight;
        ms.pdf = lobe_mixture_pdf(bsdf, si, wi, n, classes, bs.wo);
    }
    return ms;
}

} // namespace mvpt
