// Textures: spatially varying colours and scalars looked up by surface uv, or read from the
// mesh that was hit (mesh attributes).
#pragma once

#include "../core/math.h"
#include "../core/properties.h"
#include "interaction.h"

namespace mvpt {

class Texture : public Object {
public:
    /// RGB value at a surface point: at its uv, or read from its mesh (reads_mesh()).
    Color3f eval(const SurfaceInteraction &si) const { return m_reads_mesh ? eval_mesh(si) : eval(si.uv); }
    /// Scalar value at a surface point (as eval_1(uv) for uv textures, the channels' mean).
    float eval_1(const SurfaceInteraction &si) const { return m_reads_mesh ? eval_mesh(si).mean() : eval_1(si.uv); }
    /// Whether the value comes from the hit mesh's attributes rather than from uv: such a
    /// texture is only evaluated at surface hits (BSDF parameters), see get_uv_texture.
    bool reads_mesh() const { return m_reads_mesh; }

    /// RGB value at texture coordinates `uv`.
    virtual Color3f eval(Vec2f uv) const = 0;
    /// Scalar value (roughness, weights): the mean of the channels.
    virtual float eval_1(Vec2f uv) const { return eval(uv).mean(); }
    /// The gradient of eval_1 in uv (bump maps); zero where it is piecewise constant.
    virtual Vec2f eval_1_grad(Vec2f uv) const {
        (void)uv;
        return {0.f, 0.f};
    }
    /// Average over the texture domain (used for light power and previews).
    virtual Color3f mean() const = 0;
    virtual bool is_constant() const { return false; }

protected:
    /// The value at a surface hit of a texture that reads the mesh (m_reads_mesh).
    virtual Color3f eval_mesh(const SurfaceInteraction &si) const { return eval(si.uv); }
    bool m_reads_mesh = false;
};

class ConstantTexture final : public Texture {
public:
    explicit ConstantTexture(Color3f c) : m_value(c) {}
    Color3f eval(Vec2f) const override { return m_value; }
    float eval_1(Vec2f) const override { return m_value.mean(); }
    Color3f mean() const override { return m_value; }
    bool is_constant() const override { return true; }

private:
    Color3f m_value;
};

/// Texture-valued parameter `name` of `props`: an `<rgb>`/`<float>`/`<spectrum>` constant (see
/// Properties::get_color) or a nested/referenced texture.
std::shared_ptr<Texture> get_texture(const Properties &props, const std::string &name, Color3f def,
                                     SpectrumUse use = SpectrumUse::Reflectance);
inline std::shared_ptr<Texture> get_texture(const Properties &props, const std::string &name, float def,
                                            SpectrumUse use = SpectrumUse::Reflectance) {
    return get_texture(props, name, Color3f(def), use);
}
/// get_texture for a parameter that is looked up by uv alone (an emitter's radiance, a bump
/// map's height, a texture's inputs): a texture that reads the mesh is refused.
std::shared_ptr<Texture> get_uv_texture(const Properties &props, const std::string &name, Color3f def,
                                        SpectrumUse use = SpectrumUse::Reflectance);

} // namespace mvpt
