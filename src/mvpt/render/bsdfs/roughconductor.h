// The rough conductor's lobe (Mitsuba 3's `roughconductor`) at one pair of directions,
// written without branches: RoughConductor evaluates it per call and as one vector loop over
// the sharing views of multi-view path tracing, and the wavefront path tracer's kernels per
// lane (integrators/path/path_kernels_conductor.cpp).
#pragma once

#include "../fresnel.h"
#include "../microfacet.h"

namespace mvpt {

/// What the lobe needs at a hit: the distribution and the conductor's colours.
struct RoughConductorLocal {
    float alpha_u = 0.1f, alpha_v = 0.1f;
    bool sample_visible = true;
    Color3f eta, k;
    Color3f specular{1.f}; ///< the specular reflectance (1 when absent)
};

/// f cos(theta_o) = F D G / (4 cos theta_i) [Walter et al. 2007, eq. 20] (if `Fv`) and the
/// density with which RoughConductor::sample produces wo (if `Pv`: the half-vector density over
/// 4 |wo.h|, eq. 14), for wi and wo in the local frame; zero below the surface. The
/// distribution is Beckmann's where `beckmann`, else GGX.
template <bool Fv, bool Pv>
[[gnu::always_inline]] inline void rough_conductor_lobe(const RoughConductorLocal &l, bool beckmann, Vec3f wi, Vec3f wo,
                                                        Color3f &f, float &pdf) {
    const bool above = !(wi.z <= 0.f) & !(wo.z <= 0.f);
    const Vec3f h = normalize(wi + wo);
    const float D = microfacet_d(h, l.alpha_u, l.alpha_v, beckmann);
    const float g1_i = microfacet_g1(wi, h, l.alpha_u, l.alpha_v, beckmann);
    if constexpr (Fv) {
        const float value = D * (g1_i * microfacet_g1(wo, h, l.alpha_u, l.alpha_v, beckmann)) / (4.f * wi.z);
        const float cos_ih = dot(wi, h);
        const bool ok = above & !(D == 0.f);
        f.r = select(ok, fresnel_conductor(cos_ih, l.eta.r, l.k.r) * value * l.specular.r, 0.f);
        f.g = select(ok, fresnel_conductor(cos_ih, l.eta.g, l.k.g) * value * l.specular.g, 0.f);
        f.b = select(ok, fresnel_conductor(cos_ih, l.eta.b, l.k.b) * value * l.specular.b, 0.f);
    }
    if constexpr (Pv) {
        const float cos_oh = dot(wo, h);
        const float p_visible = D * g1_i / (4.f * wi.z), p_normals = D * h.z / (4.f * cos_oh);
        const bool ok = above & !(dot(wi, h) <= 0.f) & !(cos_oh <= 0.f);
        pdf = select(ok, select(l.sample_visible, p_visible, p_normals), 0.f);
    }
}

/// RoughConductor::sample once a microfacet normal m has been drawn with density pdf_m.
struct RoughConductorSample {
    Vec3f wo;          ///< wi reflected about m
    float pdf = 0.f;   ///< pdf_m / (4 wo.m) [Walter et al. 2007, eq. 14]
    Color3f weight;    ///< f cos(theta_o) / pdf
    bool ok = false;   ///< false where the sample fails (then the weight is not used)
};

/// The weight is F G1(wo, m) for visible normals [Heitz 2014], else F G(wi, wo, m) (wi.m) /
/// (cos theta_i cos theta_m); branch-free.
[[gnu::always_inline]] inline RoughConductorSample rough_conductor_reflect(const RoughConductorLocal &l, bool beckmann,
                                                                          Vec3f wi, Vec3f m, float pdf_m) {
    RoughConductorSample s;
    const float cos_im = dot(wi, m);
    s.wo = reflect(wi, m);
    s.pdf = pdf_m / (4.f * dot(s.wo, m));
    const float g1_o = microfacet_g1(s.wo, m, l.alpha_u, l.alpha_v, beckmann);
    const float g = select(l.sample_visible, g1_o,
                           microfacet_g1(wi, m, l.alpha_u, l.alpha_v, beckmann) * g1_o * cos_im / (wi.z * m.z));
    s.weight = Color3f(fresnel_conductor(cos_im, l.eta.r, l.k.r) * g * l.specular.r,
                       fresnel_conductor(cos_im, l.eta.g, l.k.g) * g * l.specular.g,
                       fresnel_conductor(cos_im, l.eta.b, l.k.b) * g * l.specular.b);
    s.ok = (wi.z > 0.f) & !(pdf_m == 0.f) & !(s.wo.z <= 0.f) &
           !((s.weight.r == 0.f) & (s.weight.g == 0.f) & (s.weight.b == 0.f));
    return s;
}

} // namespace mvpt
