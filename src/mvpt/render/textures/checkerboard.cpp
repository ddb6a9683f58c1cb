// Procedural checkerboard (Mitsuba's `checkerboard`): color0 where the
// fractional parts of u and v are on the same side of 1/2, color1 elsewhere.
#include "../../core/plugin.h"
#include "../texture.h"
#include "uv_transform.h"

#include <cmath>

namespace mvpt {

class Checkerboard final : public Texture {
public:
    explicit Checkerboard(const Properties &props) {
        m_color0 = get_uv_texture(props, "color0", Color3f(0.4f));
        m_color1 = get_uv_texture(props, "color1", Color3f(0.2f));
        m_to_uv = UvTransform(props.get_transform("to_uv"));
    }

    Color3f eval(Vec2f uv) const override { return first_color(uv) ? m_color0->eval(uv) : m_color1->eval(uv); }

    /// Mitsuba 3.9's checkerboard `eval_1` picks the opposite patch colour from
    /// `eval` (a quirk of its implementation); reproduced so that scalar uses
    /// (e.g. roughness) agree with Mitsuba.
    float eval_1(Vec2f uv) const override { return first_color(uv) ? m_color1->eval_1(uv) : m_color0->eval_1(uv); }

    Color3f mean() const override { return (m_color0->mean() + m_color1->mean()) * 0.5f; }

private:
    bool first_color(Vec2f uv) const {
        Vec2f p = m_to_uv(uv);
        bool mu = p.x - std::floor(p.x) > 0.5f, mv = p.y - std::floor(p.y) > 0.5f;
        return mu == mv;
    }

    std::shared_ptr<Texture> m_color0, m_color1;
    UvTransform m_to_uv;
};

MVPT_REGISTER_PLUGIN("texture", "checkerboard", [](const Properties &p, const LoadContext &) {
    return std::make_shared<Checkerboard>(p);
});

} // namespace mvpt
