// Textures: spatially varying colours and scalars looked up by surface uv.
#pragma once

#include "../core/math.h"
#include "../core/properties.h"

namespace mvpt {

class Texture : public Object {
public:
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

} // namespace mvpt
