// The `heterogeneous` medium: sigma_t and albedo given as volumes (grids or constants), times
// `scale`. Free flights by delta tracking against the majorant max(sigma_t) [Woodcock 1965],
// in RGB as spectral tracking: a tentative collision is real with probability
// mean(sigma_t) / majorant and weights each channel by what its own collision density asks
// (sigma_s / mean(sigma_t) when real, (majorant - sigma_t) / (majorant - mean(sigma_t)) when
// null; both at most 3), so every channel stays unbiased [Kutz et al. 2017]. Transmittance by
// ratio tracking [Novák et al. 2014]. Outside the extinction volume's box the medium is empty.
#include "../../core/plugin.h"
#include "../medium.h"
#include "../volume.h"

namespace mvpt {

namespace {

/// Tentative collisions one flight may take before it is given up (weight 0): a guard against
/// a majorant times distance so large that the walk would not end in reasonable time.
constexpr int MaxCollisions = 1 << 22;

class Heterogeneous final : public Medium {
public:
    explicit Heterogeneous(const Properties &props) {
        read_common(props);
        m_scale = props.get_float("scale", 1.f);
        if (!(m_scale >= 0.f) || !std::isfinite(m_scale)) props.fail("scale", "scale must be finite and >= 0");
        m_sigma_t = get_volume(props, "sigma_t", Color3f(1.f), SpectrumUse::Unbounded);
        m_albedo = get_volume(props, "albedo", Color3f(0.75f), SpectrumUse::Reflectance);
        check_volume_range(props, "sigma_t", *m_sigma_t, 0.f, Infinity, "an extinction coefficient");
        check_volume_range(props, "albedo", *m_albedo, 0.f, 1.f, "the scattering share of extinction");
        m_majorant = m_sigma_t->max_value() * m_scale;
        if (!std::isfinite(m_majorant) || m_majorant < 0.f) props.fail("sigma_t", "the extinction must be finite and >= 0");
        m_bounds = m_sigma_t->bounds();
    }

    MediumSample sample(const Ray &ray, float t_surface, float u, RandomStream &rs) const override {
        MediumSample ms;
        ms.t = t_surface;
        float t0, t1;
        if (!clip(ray, t_surface, t0, t1) || !(m_majorant > 0.f)) return ms;
        Spectrum w(1.f);
        float t = t0;
        for (int i = 0; i < MaxCollisions; ++i) {
            t -= std::log1p(-(i == 0 ? u : rs.next_1d())) / m_majorant;
            if (!(t < t1)) {
                ms.weight = w;
                return ms;
            }
            const Point3f p = ray.at(t);
            const Spectrum sigma_t = m_sigma_t->eval(p) * m_scale;
            const float mean = (sigma_t[0] + sigma_t[1] + sigma_t[2]) * (1.f / 3.f);
            if (rs.next_1d() * m_majorant < mean) {
                ms.scattered = true, ms.t = t;
                ms.weight = w * sigma_t * m_albedo->eval(p) * (1.f / mean);
                return ms;
            }
            w *= (Spectrum(m_majorant) - sigma_t) * (1.f / (m_majorant - mean));
        }
        ms.weight = Spectrum(0.f);
        return ms;
    }

    Spectrum transmittance(const Ray &ray, float t, RandomStream &rs) const override {
        float t0, t1;
        if (!clip(ray, t, t0, t1) || !(m_majorant > 0.f)) return Spectrum(1.f);
        Spectrum tr(1.f);
        float s = t0;
        for (int i = 0; i < MaxCollisions; ++i) {
            s -= std::log1p(-rs.next_1d()) / m_majorant;
            if (!(s < t1)) return tr;
            tr *= Spectrum(1.f) - m_sigma_t->eval(ray.at(s)) * (m_scale / m_majorant);
            if (tr.is_black()) return tr;
        }
        return Spectrum(0.f);
    }

private:
    /// The part [t0, t1) of [0, t_max) inside the extinction's box; false when empty.
    bool clip(const Ray &ray, float t_max, float &t0, float &t1) const {
        t0 = 0.f, t1 = t_max;
        for (int a = 0; a < 3; ++a) {
            const float inv = 1.f / ray.d[a];
            float near = (m_bounds.min[a] - ray.o[a]) * inv, far = (m_bounds.max[a] - ray.o[a]) * inv;
            if (near > far) std::swap(near, far);
            if (!std::isnan(near)) t0 = std::max(t0, near);
            if (!std::isnan(far)) t1 = std::min(t1, far);
        }
        return t0 < t1;
    }

    std::shared_ptr<Volume> m_sigma_t, m_albedo;
    float m_scale = 1.f, m_majorant = 0.f;
    BoundingBox m_bounds;
};

} // namespace

MVPT_REGISTER_PLUGIN("medium", "heterogeneous", [](const Properties &p, const LoadContext &) {
    return std::make_shared<Heterogeneous>(p);
});

} // namespace mvpt
