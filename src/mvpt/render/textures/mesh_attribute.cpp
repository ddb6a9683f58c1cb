// Mesh attribute (Mitsuba's `mesh_attribute`): the value of a named per-vertex or per-face
// attribute of the mesh that was hit ("vertex_color", "face_weight"), times `scale`. Vertex
// attributes are interpolated with the hit's barycentrics; face attributes are constant over a
// face. Only a BSDF's parameters can be one (get_uv_texture), and every shape whose BSDF reads
// it must have the attribute (checked when the scene is loaded).
#include "../../core/plugin.h"
#include "../shape.h"
#include "../texture.h"

namespace mvpt {

class MeshAttributeTexture final : public Texture {
public:
    explicit MeshAttributeTexture(const Properties &props) {
        m_name = props.get_string("name");
        if (!m_name.starts_with("vertex_") && !m_name.starts_with("face_"))
            props.fail("name", "mesh_attribute 'name' must start with 'vertex_' or 'face_', got '" + m_name + "'");
        m_scale = props.get_float("scale", 1.f);
        m_reads_mesh = true;
        mesh_attributes = {m_name};
    }

    /// Not looked up by uv (get_uv_texture refuses it there): black.
    Color3f eval(Vec2f) const override { return Color3f(0.f); }
    /// Not known without the mesh; only sampling weights (plastic's) use it.
    Color3f mean() const override { return Color3f(0.5f); }

private:
    Color3f eval_mesh(const SurfaceInteraction &si) const override {
        return si.shape->eval_attribute(m_name, si) * m_scale;
    }

    std::string m_name;
    float m_scale = 1.f;
};

MVPT_REGISTER_PLUGIN("texture", "mesh_attribute", [](const Properties &p, const LoadContext &) {
    return std::make_shared<MeshAttributeTexture>(p);
});

} // namespace mvpt
