// Normal-map adapter (Mitsuba 3.9's `normalmap`): the perturbed normal is the texture's
// 2 rgb - 1 in tangent space (the coordinates of the surface's shading frame), the tangent the
// shading frame's s projected off it (perturbed_frame.h).
#include "../../core/plugin.h"
#include "../texture.h"
#include "perturbed_frame.h"

namespace mvpt {

class NormalMapBsdf final : public PerturbedFrameBsdf {
public:
    explicit NormalMapBsdf(const Properties &props) : PerturbedFrameBsdf(props, "normalmap") {
        if (!props.has_texture("normalmap")) props.fail("normalmap", "normalmap needs a 'normalmap' texture");
        m_normalmap = get_texture(props, "normalmap", 0.5f, SpectrumUse::Unbounded);
    }

private:
    Perturbation perturbation(const SurfaceInteraction &si) const override {
        const Color3f c = m_normalmap->eval(si);
        return {{2.f * c.r - 1.f, 2.f * c.g - 1.f, 2.f * c.b - 1.f}, {1.f, 0.f, 0.f}};
    }

    std::shared_ptr<Texture> m_normalmap;
};

MVPT_REGISTER_PLUGIN("bsdf", "normalmap", [](const Properties &p, const LoadContext &) {
    return std::make_shared<NormalMapBsdf>(p);
});

} // namespace mvpt
