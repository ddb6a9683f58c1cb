// Bump-map adapter (Mitsuba 3.9's `bumpmap`): a height field h = scale * texture displaces the
// surface along its shading normal n; with the surface's partials (Shape::uv_partials),
// dp/du' = dp/du + n (dh/du - n.dp/du) and dp/dv' likewise, and the perturbed normal is
// dp/du' x dp/dv', turned to the side of the geometric normal. The tangent is dp/du projected
// off it (perturbed_frame.h).
#include "../../core/plugin.h"
#include "../shape.h"
#include "../texture.h"
#include "perturbed_frame.h"

namespace mvpt {

class BumpMapBsdf final : public PerturbedFrameBsdf {
public:
    explicit BumpMapBsdf(const Properties &props) : PerturbedFrameBsdf(props, "bumpmap") {
        const auto textures = props.children_of_kind("texture");
        if (textures.empty()) throw SceneError(props.loc(), "bumpmap needs a nested texture (the height field)");
        if (textures.size() > 1) throw SceneError(textures[1]->loc, "bumpmap accepts one nested texture");
        m_height = std::static_pointer_cast<Texture>(textures[0]->object);
        if (m_height->reads_mesh())
            throw SceneError(textures[0]->loc, "bumpmap differentiates its height field in uv: a mesh_attribute "
                                               "texture cannot be one");
        m_scale = props.get_float("scale", 1.f);
    }

private:
    Perturbation perturbation(const SurfaceInteraction &si) const override {
        const Vec2f grad = m_height->eval_1_grad(si.uv) * m_scale;
        const auto [dp_du, dp_dv] = surface_uv_partials(si);
        const Vec3f n = si.sh_frame.n;
        const Vec3f du = dp_du + n * (grad.x - dot(n, dp_du)), dv = dp_dv + n * (grad.y - dot(n, dp_dv));
        Vec3f m = cross(du, dv);
        if (dot(si.n, m) < 0.f) m = -m;
        return {si.to_local(m), si.to_local(dp_du)};
    }

    std::shared_ptr<Texture> m_height;
    float m_scale = 1.f;
};

MVPT_REGISTER_PLUGIN("bsdf", "bumpmap", [](const Properties &p, const LoadContext &) {
    return std::make_shared<BumpMapBsdf>(p);
});

} // namespace mvpt
