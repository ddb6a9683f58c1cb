// Normalised modified Phong BRDF plus a Lambertian term (an mvpt extension;
// Mitsuba 3 has no `phong`): f = kd / pi + ks (e + 2) / (2 pi) cos^e(alpha),
// alpha the angle between wo and the mirror direction of wi [Lafortune and
// Willems 1994, "Using the modified Phong reflectance model for physically
// based rendering"]. One-sided.
#include "../../core/plugin.h"

#include <algorithm>
#include "../../core/simd.h"
#include "../../core/warp.h"
#include "../bsdf.h"
#include "../texture.h"

namespace mvpt {

namespace {

/// The lobes of `n` viewers at one `wo` (cos(wo) > 0): f = kd + ks cos^e(alpha_c) and
/// pdf = spec_pdf cos^e(alpha_c) + diffuse_pdf, zero for viewers below the surface; cos^e by
/// repeated squaring when `int_e` >= 0 (the same products as PhongBsdf::lobe_power). Views
/// in chunks, each step a branch-free loop over the chunk.
MVPT_MULTI_ISA void phong_lobes(const Vec3f *__restrict wi, size_t n, Vec3f wo, int int_e, float e, Spectrum kd,
                                Spectrum ks, float spec_pdf, float diffuse_pdf, Spectrum *__restrict f,
                                float *__restrict pdf) {
    constexpr size_t Chunk = 64;
    for (size_t c0 = 0; c0 < n; c0 += Chunk) {
        const size_t m = std::min(Chunk, n - c0);
        float base[Chunk], lobe[Chunk];
        for (size_t c = 0; c < m; ++c) {
            const Vec3f w = wi[c0 + c];
            float cos_a = dot(wo, Vec3f(-w.x, -w.y, w.z)); // wo . mirror(w), as in eval
            base[c] = cos_a > 0.f ? cos_a : 0.f;
            lobe[c] = 1.f;
        }
        if (int_e >= 0) {
            for (int k = int_e; k > 0; k >>= 1) {
                if (k & 1)
                    for (size_t c = 0; c < m; ++c) lobe[c] *= base[c];
                for (size_t c = 0; c < m; ++c) base[c] *= base[c];
            }
        } else {
            for (size_t c = 0; c < m; ++c) lobe[c] = std::pow(base[c], e);
        }
        for (size_t c = 0; c < m; ++c) {
            const bool front = wi[c0 + c].z > 0.f;
            const float l = lobe[c];
            f[c0 + c] = Spectrum(select(front, kd.r + ks.r * l, 0.f), select(front, kd.g + ks.g * l, 0.f),
                                 select(front, kd.b + ks.b * l, 0.f));
            pdf[c0 + c] = select(front, spec_pdf * l + diffuse_pdf, 0.f);
        }
    }
}

} // namespace

class PhongBsdf final : public Bsdf {
public:
    explicit PhongBsdf(const Properties &props) {
        m_exponent = get_texture(props, "exponent", 30.f);
        m_specular_reflectance = get_texture(props, "specular_reflectance", 0.2f);
        m_diffuse_reflectance = get_texture(props, "diffuse_reflectance", 0.5f);
        m_flags = BsdfGlossyReflection | BsdfDiffuseReflection;
        // Constant parameters (the usual case) are evaluated once: pdf and eval are then a few
        // flops and one pow (multi-view path tracing evaluates them for every pair of views).
        m_constant = m_exponent->is_constant() && m_specular_reflectance->is_constant() &&
                     m_diffuse_reflectance->is_constant();
        if (m_constant) {
            SurfaceInteraction si;
            m_const_exponent = exponent_at(si);
            m_const_p_spec = specular_probability_at(si);
            m_const_kd = m_diffuse_reflectance->eval(si);
            m_const_ks = m_specular_reflectance->eval(si);
            // Small integer exponents (the usual choice) take a few multiplications instead of pow.
            if (m_const_exponent == std::floor(m_const_exponent) && m_const_exponent <= 64.f)
                m_int_exponent = int(m_const_exponent);
        }
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const override {
        BsdfSample bs;
        if (Frame::cos_theta(wi) <= 0.f) return {bs, {}};
        if (u1 < specular_probability(si)) {
            // cos^e lobe around the mirror direction: cos(alpha) = u^(1/(e+1)).
            float e = exponent(si);
            float cos_a = std::pow(u2.x, 1.f / (e + 1.f)), sin_a = safe_sqrt(1.f - cos_a * cos_a);
            float phi = 2.f * Pi * u2.y;
            Frame lobe(Vec3f(-wi.x, -wi.y, wi.z));
            bs.wo = lobe.to_world(Vec3f(sin_a * std::cos(phi), sin_a * std::sin(phi), cos_a));
            bs.sampled_type = BsdfGlossyReflection;
        } else {
            bs.wo = warp::square_to_cosine_hemisphere(u2);
            bs.sampled_type = BsdfDiffuseReflection;
        }
        bs.pdf = pdf(ctx, si, wi, bs.wo);
        if (!(bs.pdf > 0.f)) return {bs, {}};
        return {bs, eval(ctx, si, wi, bs.wo) / bs.pdf};
    }

    Spectrum eval(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        float cos_i = Frame::cos_theta(wi), cos_o = Frame::cos_theta(wo);
        if (cos_i <= 0.f || cos_o <= 0.f) return {};
        float e = exponent(si);
        float cos_a = std::max(0.f, dot(wo, Vec3f(-wi.x, -wi.y, wi.z)));
        float spec = (e + 2.f) * InvTwoPi * lobe_power(cos_a, e);
        return (diffuse(si) * InvPi + specular(si) * spec) * cos_o;
    }

    /// Mixture of the lobe densities; zero below the surface, where `sample` returns no weight.
    float pdf(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        if (Frame::cos_theta(wi) <= 0.f || Frame::cos_theta(wo) <= 0.f) return 0.f;
        float p_spec = specular_probability(si), e = exponent(si);
        float cos_a = std::max(0.f, dot(wo, Vec3f(-wi.x, -wi.y, wi.z)));
        float pdf_spec = (e + 1.f) * InvTwoPi * lobe_power(cos_a, e);
        return p_spec * pdf_spec + (1.f - p_spec) * warp::square_to_cosine_hemisphere_pdf(wo);
    }

    /// One cos^e for both (multi-view path tracing evaluates every sharing view's lobe).
    std::pair<Spectrum, float> eval_pdf(const BsdfContext &, const SurfaceInteraction &si, Vec3f wi,
                                        Vec3f wo) const override {
        float cos_i = Frame::cos_theta(wi), cos_o = Frame::cos_theta(wo);
        if (cos_i <= 0.f || cos_o <= 0.f) return {Spectrum(0.f), 0.f};
        float e = exponent(si), p_spec = specular_probability(si);
        float cos_a = std::max(0.f, dot(wo, Vec3f(-wi.x, -wi.y, wi.z)));
        float lobe = lobe_power(cos_a, e) * InvTwoPi;
        Spectrum f = (diffuse(si) * InvPi + specular(si) * ((e + 2.f) * lobe)) * cos_o;
        float pdf = p_spec * (e + 1.f) * lobe + (1.f - p_spec) * warp::square_to_cosine_hemisphere_pdf(wo);
        return {f, pdf};
    }

    /// The lobes of many viewers at one `wo`: the parameters and cos(wo) once, then per viewer
    /// one cos^e.
    void eval_pdf_views(const BsdfContext &, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        float cos_o = Frame::cos_theta(wo);
        if (cos_o <= 0.f) {
            std::fill(f, f + n, Spectrum(0.f));
            std::fill(pdf, pdf + n, 0.f);
            return;
        }
        const float e = exponent(si), p_spec = specular_probability(si);
        const Spectrum kd = diffuse(si) * (InvPi * cos_o), ks = specular(si) * ((e + 2.f) * InvTwoPi * cos_o);
        const float spec_pdf = p_spec * (e + 1.f) * InvTwoPi, diffuse_pdf = (1.f - p_spec) * InvPi * cos_o;
        phong_lobes(wi, n, wo, m_int_exponent, e, kd, ks, spec_pdf, diffuse_pdf, f, pdf);
    }

    /// GGX-equivalent roughness of the lobe: alpha = sqrt(2 / (e + 2)).
    float roughness(const SurfaceInteraction &si) const override { return std::sqrt(2.f / (exponent(si) + 2.f)); }

private:
    /// cos^e by repeated squaring when e is a constant integer, else pow.
    float lobe_power(float c, float e) const {
        if (m_int_exponent < 0) return std::pow(c, e);
        float r = 1.f;
        for (int k = m_int_exponent; k > 0; k >>= 1, c *= c)
            if (k & 1) r *= c;
        return r;
    }
    Spectrum diffuse(const SurfaceInteraction &si) const { return m_constant ? m_const_kd : m_diffuse_reflectance->eval(si); }
    Spectrum specular(const SurfaceInteraction &si) const { return m_constant ? m_const_ks : m_specular_reflectance->eval(si); }
    float exponent(const SurfaceInteraction &si) const { return m_constant ? m_const_exponent : exponent_at(si); }
    float specular_probability(const SurfaceInteraction &si) const {
        return m_constant ? m_const_p_spec : specular_probability_at(si);
    }
    float exponent_at(const SurfaceInteraction &si) const { return std::max(m_exponent->eval_1(si), 0.f); }
    /// Lobe choice in proportion to the mean (over channels) specular and diffuse reflectances at `si`.
    float specular_probability_at(const SurfaceInteraction &si) const {
        float ks = m_specular_reflectance->eval(si).mean(), kd = m_diffuse_reflectance->eval(si).mean();
        return ks + kd > 0.f ? ks / (ks + kd) : 0.5f;
    }

    std::shared_ptr<Texture> m_exponent, m_specular_reflectance, m_diffuse_reflectance;
    bool m_constant = false;
    float m_const_exponent = 0.f, m_const_p_spec = 0.f;
    Spectrum m_const_kd{0.f}, m_const_ks{0.f};
    int m_int_exponent = -1; ///< the exponent when it is a constant integer <= 64, else -1
};

MVPT_REGISTER_PLUGIN("bsdf", "phong", [](const Properties &p, const LoadContext &) {
    return std::make_shared<PhongBsdf>(p);
});

} // namespace mvpt
