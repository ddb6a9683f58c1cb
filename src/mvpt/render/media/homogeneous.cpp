// The `homogeneous` medium: a constant sigma_t (or sigma_a + sigma_s) times `scale`, and an
// albedo that may vary in space (a volume, as in Mitsuba). Free flights are drawn exactly per
// channel (see medium.h for the channel mixture); transmittance is exp(-sigma_t t).
#include "../../core/plugin.h"
#include "../medium.h"
#include "../volume.h"

namespace mvpt {

namespace {

class Homogeneous final : public Medium {
public:
    explicit Homogeneous(const Properties &props) {
        read_common(props);
        float scale = props.get_float("scale", 1.f);
        if (!(scale >= 0.f) || !std::isfinite(scale)) props.fail("scale", "scale must be finite and >= 0");
        Color3f sigma_t;
        if (props.has("sigma_a") || props.has("sigma_s")) {
            for (const char *other : {"sigma_t", "albedo"})
                if (props.has(other))
                    props.fail(other, std::string("give either sigma_t and albedo or sigma_a and sigma_s, not ") + other +
                                          " with them");
            Color3f a = props.get_color("sigma_a", Color3f(0.f), SpectrumUse::Unbounded);
            Color3f s = props.get_color("sigma_s", Color3f(0.f), SpectrumUse::Unbounded);
            check_volume_range(props, "sigma_a", *constant_volume(a), 0.f, Infinity, "an absorption coefficient");
            check_volume_range(props, "sigma_s", *constant_volume(s), 0.f, Infinity, "a scattering coefficient");
            sigma_t = a + s;
            Color3f albedo;
            for (int c = 0; c < 3; ++c) albedo[c] = sigma_t[c] > 0.f ? s[c] / sigma_t[c] : 0.f;
            m_albedo = constant_volume(albedo);
        } else {
            if (!get_volume(props, "sigma_t", Color3f(1.f), SpectrumUse::Unbounded)->constant(sigma_t))
                props.fail("sigma_t", "a homogeneous medium needs a constant sigma_t: use a 'heterogeneous' medium for a grid");
            m_albedo = get_volume(props, "albedo", Color3f(0.75f), SpectrumUse::Reflectance);
            check_volume_range(props, "albedo", *m_albedo, 0.f, 1.f, "the scattering share of extinction");
        }
        for (int c = 0; c < 3; ++c)
            if (!(sigma_t[c] >= 0.f) || !std::isfinite(sigma_t[c] * scale))
                props.fail("", "the medium's extinction must be finite and >= 0");
        m_sigma_t = sigma_t * scale;
    }

    float free_flight_bound(float u) const override { return distance(u); }

    MediumSample sample(const Ray &ray, float t_surface, float u, RandomStream &) const override {
        const float t = distance(u);
        MediumSample ms;
        ms.scattered = t < t_surface;
        ms.t = ms.scattered ? t : t_surface;
        Spectrum tr = exp_tr(ms.t);
        // Density of the mixture over channels: of t (scattering) or of passing t_surface.
        float pdf = 0.f;
        for (int i = 0; i < 3; ++i) pdf += (ms.scattered ? m_sigma_t[i] * tr[i] : tr[i]) * (1.f / 3.f);
        if (!(pdf > 0.f)) ms.weight = Spectrum(0.f);
        else ms.weight = (ms.scattered ? tr * m_sigma_t * m_albedo->eval(ray.at(ms.t)) : tr) * (1.f / pdf);
        return ms;
    }

    Spectrum transmittance(const Ray &, float t, RandomStream &) const override { return exp_tr(t); }

    bool constant_extinction(Spectrum &sigma_t) const override {
        sigma_t = m_sigma_t;
        return true;
    }
    Spectrum scattering(Point3f p) const override { return m_sigma_t * m_albedo->eval(p); }

    bool sample_within(const Ray &ray, float t_end, float u, MediumSample &out) const override {
        // The channel mixture of `sample`, each channel's exponential truncated to [0, t_end):
        //   p(t) = 1/3 sum_c sigma_c exp(-sigma_c t) / (1 - exp(-sigma_c t_end)).
        Spectrum mass; // 1 - exp(-sigma_c t_end), exact for thin segments
        for (int i = 0; i < 3; ++i) mass[i] = -std::expm1(-m_sigma_t[i] * t_end);
        float u3 = u * 3.f;
        int c = std::min(int(u3), 2);
        float uc = std::min(u3 - float(c), OneMinusEpsilon);
        out = MediumSample{};
        if (!(mass[c] > 0.f)) return true; // this channel cannot scatter here
        const float t = std::min(-std::log1p(-uc * mass[c]) / m_sigma_t[c], t_end);
        const Spectrum tr = exp_tr(t);
        float pdf = 0.f;
        for (int i = 0; i < 3; ++i)
            if (mass[i] > 0.f) pdf += m_sigma_t[i] * tr[i] / mass[i] * (1.f / 3.f);
        if (!(pdf > 0.f)) return true;
        out.scattered = true;
        out.t = t;
        out.weight = tr * m_sigma_t * m_albedo->eval(ray.at(t)) * (1.f / pdf);
        return true;
    }

private:
    /// Channel c = floor(3u); the rest of u draws t ~ sigma_c exp(-sigma_c t).
    float distance(float u) const {
        float u3 = u * 3.f;
        int c = std::min(int(u3), 2);
        float uc = std::min(u3 - float(c), OneMinusEpsilon);
        return m_sigma_t[c] > 0.f ? -std::log1p(-uc) / m_sigma_t[c] : Infinity;
    }

    /// exp(-sigma_t t) per channel; an infinite t gives 0 where sigma_t > 0 and 1 where it is 0.
    Spectrum exp_tr(float t) const {
        Spectrum r;
        for (int i = 0; i < 3; ++i) r[i] = m_sigma_t[i] > 0.f ? std::exp(-m_sigma_t[i] * t) : 1.f;
        return r;
    }

    Spectrum m_sigma_t;
    std::shared_ptr<Volume> m_albedo;
};

} // namespace

MVPT_REGISTER_PLUGIN("medium", "homogeneous", [](const Properties &p, const LoadContext &) {
    return std::make_shared<Homogeneous>(p);
});

} // namespace mvpt
