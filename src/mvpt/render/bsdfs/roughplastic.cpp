// Rough plastic: a diffuse base under a rough dielectric coating (Mitsuba 3's
// `roughplastic`): microfacet reflection plus a diffuse term attenuated by the
// coating's precomputed rough transmittance and internal reflectance
// [Weidlich and Wilkie 2007; Mitsuba's tabulation]. One-sided, isotropic.
#include "../../core/simd.h"
#include "../../core/quadrature.h"
#include "../../core/warp.h"
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../bsdf_views.h"
#include "../fresnel.h"
#include "../ior.h"
#include "../microfacet.h"
#include "../texture.h"

#include <tbb/parallel_for.h>

#include <array>
#include <map>
#include <mutex>
#include <tuple>
#include <utility>

namespace mvpt {

namespace {

/// Resolution of the tabulated external transmittance over cos(theta) (Mitsuba's value).
constexpr int TransmittanceRes = 64;

/// Gauss-Legendre rule of `n` points, computed once per size.
const std::pair<std::vector<float>, std::vector<float>> &gauss_legendre_cached(int n) {
    static std::mutex mutex;
    static std::map<int, std::pair<std::vector<float>, std::vector<float>>> cache;
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find(n);
    if (it == cache.end()) {
        it = cache.emplace(n, std::pair<std::vector<float>, std::vector<float>>{}).first;
        gauss_legendre(n, it->second.first, it->second.second);
    }
    return it->second;
}

/// Albedo of microfacet reflection (`transmission` false) or transmission
/// through a dielectric with relative IOR `eta`, seen from `wi`: the visible-normal
/// estimator G1(wo, m) F (or 1 - F) integrated over the unit square with a
/// tensor Gauss-Legendre rule (32^2 nodes for eta > 1, 128^2 otherwise), as Mitsuba.
float microfacet_albedo(const MicrofacetDistribution &distr, Vec3f wi, float eta, bool transmission) {
    const auto &[nodes, weights] = gauss_legendre_cached(eta > 1.f ? 32 : 128);
    double sum = 0.0;
    for (size_t j = 0; j < nodes.size(); ++j)
        for (size_t i = 0; i < nodes.size(); ++i) {
            Vec2f u(0.5f * nodes[i] + 0.5f, 0.5f * nodes[j] + 0.5f);
            Vec3f m = distr.sample(wi, u, nullptr);
            FresnelDielectric fr = fresnel_dielectric(dot(wi, m), eta);
            float value;
            if (transmission) {
                Vec3f wo = refract(wi, m, fr.cos_theta_t, fr.eta_ti);
                value = wo.z * wi.z >= 0.f ? 0.f : distr.smith_g1(wo, m) * (1.f - fr.F);
            } else {
                Vec3f wo = reflect(wi, m);
                value = (wo.z <= 0.f || wi.z <= 0.f) ? 0.f : distr.smith_g1(wo, m) * fr.F;
            }
            sum += double(value) * weights[i] * weights[j] * 0.25;
        }
    return float(sum);
}

/// Tabulated coating of a rough plastic: transmittance t(mu) into the base and the
/// base's internal diffuse reflectance, for one (distribution, alpha, eta).
struct CoatingTables {
    std::array<float, TransmittanceRes> external_transmittance;
    float internal_reflectance;
};

/// Build (or fetch from a process-wide cache: scenes repeat materials) the coating
/// tables, always with visible-normal sampling as Mitsuba does.
std::shared_ptr<const CoatingTables> coating_tables(MicrofacetType type, float alpha, float eta) {
    static std::mutex mutex;
    static std::map<std::tuple<int, float, float>, std::shared_ptr<const CoatingTables>> cache;
    auto key = std::make_tuple(int(type), alpha, eta);
    {
        std::lock_guard<std::mutex> lock(mutex);
        if (auto it = cache.find(key); it != cache.end()) return it->second;
    }
    auto t = std::make_shared<CoatingTables>();
    MicrofacetDistribution distr(type, alpha, alpha, true);
    std::array<float, TransmittanceRes> internal_terms;
    tbb::parallel_for(0, TransmittanceRes, [&](int i) {
        float mu = std::max(1e-6f, float(i) / float(TransmittanceRes - 1));
        Vec3f wi(std::sqrt(1.f - mu * mu), 0.f, mu);
        t->external_transmittance[i] = microfacet_albedo(distr, wi, eta, true);
        internal_terms[i] = microfacet_albedo(distr, wi, 1.f / eta, false) * mu;
    });
    double internal = 0.0;
    for (float v : internal_terms) internal += v;
    t->internal_reflectance = float(internal / TransmittanceRes) * 2.f;
    std::lock_guard<std::mutex> lock(mutex);
    return cache.emplace(key, t).first->second;
}

/// What the rough plastic's lobe needs at a hit: the coating's constants and tables, and the
/// textures' values there.
struct RoughPlasticLocal {
    float alpha = 0.1f, eta = 1.5f, inv_eta_2 = 1.f, specular_sampling_weight = 0.5f;
    bool sample_visible = true;
    const float *transmittance = nullptr; ///< CoatingTables::external_transmittance
    Spectrum specular{1.f};               ///< the specular reflectance (1 when absent)
    /// The diffuse reflectance over 1 - (its product with) the internal reflectance.
    Spectrum diffuse_scaled{0.f};
};

/// The coating's transmittance towards cos_theta (in [0, 1]), linear in its table.
[[gnu::always_inline]] inline float coating_transmittance(const float *t, float cos_theta) {
    const float x = cos_theta * float(TransmittanceRes - 1);
    const int idx = std::clamp(int(x), 0, TransmittanceRes - 2);
    return lerp(x - float(idx), t[idx], t[idx + 1]);
}

/// The probability of sampling the coating's lobe given its transmittance t_i towards wi.
[[gnu::always_inline]] inline float specular_probability(const RoughPlasticLocal &l, float t_i) {
    const float ps = (1.f - t_i) * l.specular_sampling_weight, pd = t_i * (1.f - l.specular_sampling_weight);
    return ps / (ps + pd);
}

/// f cos(theta_o) (if `Fv`): the coating's microfacet reflection plus the diffuse base seen
/// through it; and the density of RoughPlastic::sample producing wo (if `Pv`), sharing the
/// half vector, D, G1(wi) and the coating's transmittance towards wi. Zero below the surface;
/// branch-free, so the loop over views vectorises. Beckmann's distribution where `beckmann`, else GGX.
template <bool Fv, bool Pv>
[[gnu::always_inline]] inline void rough_plastic_lobe(const RoughPlasticLocal &l, bool beckmann, Vec3f wi, Vec3f wo,
                                                      Spectrum &f, float &pdf) {
    const float cos_theta_i = Frame::cos_theta(wi), cos_theta_o = Frame::cos_theta(wo);
    const bool above = !(cos_theta_i <= 0.f) & !(cos_theta_o <= 0.f);
    const Vec3f h = normalize(wo + wi);
    const float D = microfacet_d(h, l.alpha, l.alpha, beckmann);
    const float t_i = coating_transmittance(l.transmittance, cos_theta_i);
    const float g1_i = microfacet_g1(wi, h, l.alpha, l.alpha, beckmann);
    if constexpr (Fv) {
        const float fr = fresnel_dielectric(dot(wi, h), l.eta).F;
        const float value = fr * D * (g1_i * microfacet_g1(wo, h, l.alpha, l.alpha, beckmann)) / (4.f * cos_theta_i);
        const float base = InvPi * l.inv_eta_2 * cos_theta_o * t_i * coating_transmittance(l.transmittance, cos_theta_o);
        f.r = select(above, value * l.specular.r + l.diffuse_scaled.r * base, 0.f);
        f.g = select(above, value * l.specular.g + l.diffuse_scaled.g * base, 0.f);
        f.b = select(above, value * l.specular.b + l.diffuse_scaled.b * base, 0.f);
    }
    if constexpr (Pv) {
        const float prob_specular = specular_probability(l, t_i);
        const float p_spec = select(l.sample_visible, D * g1_i / (4.f * cos_theta_i), D * h.z / (4.f * dot(wo, h)));
        const float p = prob_specular * p_spec + (1.f - prob_specular) * (cos_theta_o * InvPi);
        pdf = select(above, p, 0.f);
    }
}

} // namespace

/// rough_plastic_lobe<true, true> for the directions wi[0..n) and one wo: one vector loop.
MVPT_MULTI_ISA void rough_plastic_lobe_views(const RoughPlasticLocal &l, bool beckmann, const Vec3f *wi, size_t n,
                                             Vec3f wo, Spectrum *f, float *pdf) {
    // One loop per distribution, its formulas alone in each.
    if (beckmann)
        lobe_over_views(wi, n, f, pdf, [&](Vec3f w, Spectrum &fc, float &pc) __attribute__((always_inline)) {
            rough_plastic_lobe<true, true>(l, true, w, wo, fc, pc);
        });
    else
        lobe_over_views(wi, n, f, pdf, [&](Vec3f w, Spectrum &fc, float &pc) __attribute__((always_inline)) {
            rough_plastic_lobe<true, true>(l, false, w, wo, fc, pc);
        });
}

class RoughPlastic final : public Bsdf {
public:
    explicit RoughPlastic(const Properties &props) {
        float int_ior = read_ior(props, "int_ior", "polypropylene"), ext_ior = read_ior(props, "ext_ior", "air");
        if (int_ior == ext_ior) props.fail("int_ior", "the interior and exterior indices of refraction must differ");
        m_eta = int_ior / ext_ior;
        m_diffuse_reflectance = get_texture(props, "diffuse_reflectance", 0.5f);
        if (props.has_texture("specular_reflectance"))
            m_specular_reflectance = get_texture(props, "specular_reflectance", 1.f);
        m_nonlinear = props.get_bool("nonlinear", false);
        read_roughness(props);
        m_flags = BsdfGlossyReflection | BsdfDiffuseReflection;

        m_inv_eta_2 = 1.f / (m_eta * m_eta);
        float d_mean = m_diffuse_reflectance->mean().mean();
        float s_mean = m_specular_reflectance ? m_specular_reflectance->mean().mean() : 1.f;
        m_specular_sampling_weight = s_mean / (d_mean + s_mean);

        m_coating = coating_tables(m_type, m_alpha, m_eta);
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const override {
        BsdfSample bs;
        float cos_theta_i = Frame::cos_theta(wi);
        if (cos_theta_i <= 0.f) return {bs, {}};
        if (u1 < specular_probability(cos_theta_i)) {
            Vec3f m = distribution().sample(wi, u2, nullptr);
            bs.wo = reflect(wi, m);
            bs.sampled_type = BsdfGlossyReflection;
        } else {
            bs.wo = warp::square_to_cosine_hemisphere(u2);
            bs.sampled_type = BsdfDiffuseReflection;
        }
        const auto [f, pdf] = eval_pdf(ctx, si, wi, bs.wo);
        bs.pdf = pdf;
        if (!(bs.pdf > 0.f)) return {bs, {}};
        return {bs, f / bs.pdf};
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        Spectrum f;
        float pdf;
        if (below(wi, wo)) return f;
        const RoughPlasticLocal l = at(si);
        with_distribution(beckmann(), [&](auto b) { rough_plastic_lobe<true, false>(l, b, wi, wo, f, pdf); });
        return f;
    }

    float pdf(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        Spectrum f;
        float pdf = 0.f;
        if (below(wi, wo)) return pdf;
        const RoughPlasticLocal l = constants();
        with_distribution(beckmann(), [&](auto b) { rough_plastic_lobe<false, true>(l, b, wi, wo, f, pdf); });
        return pdf;
    }

    std::pair<Spectrum, float> eval_pdf(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi,
                                        Vec3f wo) const override {
        std::pair<Spectrum, float> out{Spectrum(0.f), 0.f};
        if (below(wi, wo)) return out;
        const RoughPlasticLocal l = at(si);
        with_distribution(beckmann(), [&](auto b) { rough_plastic_lobe<true, true>(l, b, wi, wo, out.first, out.second); });
        return out;
    }

    /// The textures once for all the views, and one vector loop over them.
    void eval_pdf_views(const BsdfContext &, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        rough_plastic_lobe_views(at(si), beckmann(), wi, n, wo, f, pdf);
    }

    float roughness(const SurfaceInteraction &) const override { return m_alpha; }

private:
    /// The lobe's parameters that do not vary over the surface.
    RoughPlasticLocal constants() const {
        RoughPlasticLocal l;
        l.alpha = distribution().alpha_u(), l.eta = m_eta, l.inv_eta_2 = m_inv_eta_2;
        l.specular_sampling_weight = m_specular_sampling_weight;
        l.sample_visible = m_sample_visible;
        l.transmittance = m_coating->external_transmittance.data();
        return l;
    }
    /// The lobe's parameters at a hit.
    RoughPlasticLocal at(const SurfaceInteraction &si) const {
        RoughPlasticLocal l = constants();
        const Spectrum diffuse = m_diffuse_reflectance->eval(si);
        const Spectrum denom = m_nonlinear ? Spectrum(1.f) - diffuse * m_coating->internal_reflectance
                                           : Spectrum(1.f - m_coating->internal_reflectance);
        l.diffuse_scaled = diffuse / denom;
        if (m_specular_reflectance) l.specular = m_specular_reflectance->eval(si);
        return l;
    }

    /// `alpha` (float, default 0.1), or equal `alpha_u`/`alpha_v`; anisotropy is rejected as by Mitsuba.
    void read_roughness(const Properties &props) {
        m_type = MicrofacetType::Beckmann;
        if (props.has("distribution")) {
            std::string d = props.get_string("distribution");
            if (!parse_microfacet_type(d, m_type))
                props.fail("distribution", "invalid distribution \"" + d + "\", must be \"beckmann\" or \"ggx\"");
        }
        m_sample_visible = props.get_bool("sample_visible", true);
        if (props.has("alpha_u") || props.has("alpha_v")) {
            if (!props.has("alpha_u") || !props.has("alpha_v"))
                props.fail(props.has("alpha_u") ? "alpha_u" : "alpha_v",
                           "both 'alpha_u' and 'alpha_v' must be specified");
            if (props.has("alpha")) props.fail("alpha", "specify either 'alpha' or 'alpha_u'/'alpha_v', not both");
            m_alpha = props.get_float("alpha_u");
            if (props.get_float("alpha_v") != m_alpha)
                props.fail("alpha_v", "roughplastic does not support anisotropic roughness");
        } else {
            m_alpha = props.get_float("alpha", 0.1f);
        }
    }
    bool beckmann() const { return m_type == MicrofacetType::Beckmann; }
    MicrofacetDistribution distribution() const {
        return MicrofacetDistribution(m_type, m_alpha, m_alpha, m_sample_visible);
    }
    float specular_probability(float cos_theta_i) const {
        const RoughPlasticLocal l = constants();
        return mvpt::specular_probability(l, coating_transmittance(l.transmittance, cos_theta_i));
    }

    MicrofacetType m_type;
    float m_alpha, m_eta, m_inv_eta_2, m_specular_sampling_weight;
    bool m_sample_visible, m_nonlinear;
    std::shared_ptr<const CoatingTables> m_coating;
    std::shared_ptr<Texture> m_diffuse_reflectance, m_specular_reflectance;
};

MVPT_REGISTER_PLUGIN("bsdf", "roughplastic", [](const Properties &p, const LoadContext &) {
    return std::make_shared<RoughPlastic>(p);
});

} // namespace mvpt
