// Spot light (Mitsuba's `spot`): a point light emitting along its local +z
// within `cutoff_angle`, at full intensity inside `beam_width` and ramping
// linearly in angle to zero between the two; optionally modulated by a
// projected texture.
#include "../../core/plugin.h"
#include "../light.h"
#include "../texture.h"

namespace mvpt {

class SpotLight final : public Light {
public:
    explicit SpotLight(const Properties &props) {
        m_to_world = props.get_animated_transform("to_world");
        m_intensity = props.get_color("intensity", Color3f(1.f), SpectrumUse::Emission);
        if (!m_intensity.is_finite() || m_intensity.r < 0 || m_intensity.g < 0 || m_intensity.b < 0)
            props.fail("intensity", "'intensity' must be finite and non-negative");
        if (props.has_texture("texture")) {
            m_texture = get_uv_texture(props, "texture", Color3f(1.f));
            if (m_texture->is_constant()) props.fail("texture", "'texture' must be spatially varying (e.g. a bitmap)");
        }
        float cutoff_deg = props.get_float("cutoff_angle", 20.f);
        float beam_deg = props.get_float("beam_width", cutoff_deg * 0.75f);
        if (!(cutoff_deg > 0.f && cutoff_deg <= 180.f))
            props.fail("cutoff_angle", "'cutoff_angle' must lie in (0, 180] degrees");
        if (!(beam_deg >= 0.f && beam_deg <= cutoff_deg))
            props.fail("beam_width", "'beam_width' must lie in [0, cutoff_angle] degrees");
        m_cutoff = deg_to_rad(cutoff_deg);
        m_beam = deg_to_rad(beam_deg);
        m_cos_cutoff = std::cos(m_cutoff);
        m_cos_beam = std::cos(m_beam);
        m_inv_transition = 1.f / (m_cutoff - m_beam);
        m_uv_factor = std::tan(m_cutoff);
        m_flags = LightDeltaPosition;
    }

    std::pair<LightSample, Spectrum> sample_li(Point3f ref, Vec2f, float time) const override {
        Transform to_world = m_to_world.eval(time);
        LightSample ls;
        ls.p = to_world.point(Point3f(0.f));
        ls.pdf = 1.f;
        ls.delta = true;
        Vec3f d = ls.p - ref;
        ls.dist = norm(d);
        if (!(ls.dist > 0.f)) return {ls, {}};
        ls.d = d / ls.dist;
        Vec3f local = normalize(to_world.inverse().vector(-ls.d));
        float falloff = falloff_curve(local.z);
        if (!(falloff > 0.f)) return {ls, {}};
        Spectrum intensity = m_intensity;
        if (m_texture) intensity *= m_texture->eval(direction_to_uv(local));
        return {ls, intensity * (falloff / (ls.dist * ls.dist))};
    }

    float pdf_li(Point3f, const SurfaceInteraction &, Vec3f) const override { return 0.f; }
    bool moves() const override { return m_to_world.is_animated(); }

private:
    /// Angular profile in [0, 1] for a local direction with z = cos_theta.
    float falloff_curve(float cos_theta) const {
        if (!(cos_theta > m_cos_cutoff)) return 0.f;
        if (cos_theta >= m_cos_beam) return 1.f;
        return (m_cutoff - safe_acos(cos_theta)) * m_inv_transition;
    }

    /// Projective texture coordinates: the cutoff cone maps onto [0, 1]^2.
    Vec2f direction_to_uv(Vec3f local) const {
        return {0.5f + 0.5f * local.x / (local.z * m_uv_factor), 0.5f + 0.5f * local.y / (local.z * m_uv_factor)};
    }

    AnimatedTransform m_to_world;
    Color3f m_intensity;
    std::shared_ptr<Texture> m_texture;
    float m_cutoff, m_beam, m_cos_cutoff, m_cos_beam, m_inv_transition, m_uv_factor;
};

MVPT_REGISTER_PLUGIN("emitter", "spot", [](const Properties &p, const LoadContext &) {
    return std::make_shared<SpotLight>(p);
});

} // namespace mvpt
