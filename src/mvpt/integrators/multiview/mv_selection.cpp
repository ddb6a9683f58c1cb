#include "mv_selection.h"

#include "../../core/sampler.h"

#include <cmath>

namespace mvpt {

namespace {
const BsdfContext SelectionCtx;

/// min/max ratio of two densities; 0 when both vanish (no evidence the lobes agree).
float density_ratio(float a, float b) {
    float hi = std::max(a, b);
    return hi > 0.f && std::isfinite(hi) ? std::min(a, b) / hi : 0.f;
}
} // namespace

ViewLobe view_lobe(const Bsdf &bsdf, const SurfaceInteraction &si, Vec3f wi) {
    ViewLobe lobe;
    lobe.wi = wi;
    lobe.mirror = Vec3f(-wi.x, -wi.y, wi.z); // reflection about the shading normal
    lobe.peak = bsdf.pdf(SelectionCtx, si, wi, lobe.mirror);
    return lobe;
}

float total_variation_peak(const Bsdf &bsdf, const SurfaceInteraction &si, const ViewLobe &a, const ViewLobe &b) {
    float q_a = density_ratio(a.peak, bsdf.pdf(SelectionCtx, si, b.wi, a.mirror));
    float q_b = density_ratio(b.peak, bsdf.pdf(SelectionCtx, si, a.wi, b.mirror));
    return 1.f - std::min(q_a, q_b);
}

float total_variation_mc(const Bsdf &bsdf, const SurfaceInteraction &si, Vec3f wi_a, Vec3f wi_b) {
    // TV = int max(0, p - q) = E_p[max(0, 1 - q/p)]; delta lobes count as fully disjoint.
    // The points are the same for every call (a scrambled (0,2)-sequence), so the estimate
    // is a fixed function of the two lobes.
    constexpr int N = 64;
    auto one_side = [&](Vec3f wi_p, Vec3f wi_q) {
        double sum = 0.0;
        for (int i = 0; i < N; ++i) {
            float u1 = (float(i) + 0.5f) / float(N);
            Vec2f u2(bits_to_unit_float(owen_scramble(reverse_bits(uint32_t(i) * 0x9e3779b9u), 0x1234567u)),
                     bits_to_unit_float(owen_scramble(reverse_bits(uint32_t(i)), 0x89abcdefu)));
            auto [bs, w] = bsdf.sample(SelectionCtx, si, wi_p, u1, u2);
            if (w.is_black() || !(bs.pdf > 0.f)) continue; // no mass produced by this point
            if (bs.sampled_type & BsdfDelta) { sum += 1.0; continue; }
            float p = bsdf.pdf(SelectionCtx, si, wi_p, bs.wo), q = bsdf.pdf(SelectionCtx, si, wi_q, bs.wo);
            if (p > 0.f) sum += std::max(0.0, 1.0 - double(q) / double(p));
        }
        return sum / N;
    };
    double tv = 0.5 * (one_side(wi_a, wi_b) + one_side(wi_b, wi_a));
    return float(std::clamp(tv, 0.0, 1.0));
}

float material_similarity(const Bsdf &bsdf, const SurfaceInteraction &si, const ViewLobe &a, const ViewLobe &b,
                          MvTotalVariation tv) {
    return material_similarity(bsdf, si, a, b, tv, bsdf.roughness(si));
}

float material_similarity(const Bsdf &bsdf, const SurfaceInteraction &si, const ViewLobe &a, const ViewLobe &b,
                          MvTotalVariation tv, float alpha) {
    if (!(bsdf.flags() & BsdfGlossy)) return 1.f; // diffuse lobes do not depend on the view
    float d = tv == MvTotalVariation::PeakRatio ? total_variation_peak(bsdf, si, a, b)
                                                : total_variation_mc(bsdf, si, a.wi, b.wi);
    // Phong exponent e maps to alpha = sqrt(2 / (e + 2)) (Bsdf::roughness).
    alpha = std::clamp(alpha, 1e-3f, 1.f);
    float one_minus = std::clamp(1.f - d, 0.f, 1.f);
    float s = one_minus >= 1.f ? 1.f : std::pow(one_minus, 1.f / alpha);
    return std::isfinite(s) ? s : 0.f;
}

} // namespace mvpt
