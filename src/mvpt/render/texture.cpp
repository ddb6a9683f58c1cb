#include "texture.h"

namespace mvpt {

std::shared_ptr<Texture> get_texture(const Properties &props, const std::string &name, Color3f def, SpectrumUse use) {
    if (const ChildObject *c = props.named_child(name)) {
        if (c->kind != "texture") props.fail(name, "parameter '" + name + "' expects a texture, got a " + c->kind);
        return std::static_pointer_cast<Texture>(c->object);
    }
    Color3f v = props.get_color(name, def, use);
    if (!v.is_finite()) props.fail(name, "parameter '" + name + "' is not finite");
    return std::make_shared<ConstantTexture>(v);
}

std::shared_ptr<Texture> get_uv_texture(const Properties &props, const std::string &name, Color3f def, SpectrumUse use) {
    std::shared_ptr<Texture> t = get_texture(props, name, def, use);
    if (t->reads_mesh())
        props.fail(name, "parameter '" + name + "' of the " + props.kind() + " '" + props.type() +
                             "' is looked up by uv: a mesh_attribute texture can only be a BSDF's parameter");
    return t;
}

} // namespace mvpt
