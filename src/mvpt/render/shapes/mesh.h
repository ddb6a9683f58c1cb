// Triangle meshes (obj, ply, serialized, rectangle, cube): world-space
// vertices in an Embree triangle geometry.
#pragma once

#include "../../core/distribution.h"
#include "../../scene/mesh_data.h"
#include "../../scene/plugin.h"
#include "../shape.h"

namespace mvpt {

class TriangleMesh : public Shape {
public:
    /// Takes `data` in object space; applies to_world, flip_normals and
    /// face_normals from `props`, and validates the data (errors at `props`' location).
    TriangleMesh(MeshData data, const Properties &props, const std::string &what);

    unsigned attach(RTCDevice device, RTCScene scene) override;
    void fill_interaction(const Ray &ray, float t, uint32_t prim, Vec2f b, SurfaceInteraction &si) const override;
    float area() const override { return m_area; }
    BoundingBox bounds() const override { return m_bounds; }
    ShapeSample sample_area(Vec2f u) const override;

    const MeshData &data() const { return m_data; }

private:
    MeshData m_data;
    bool m_flip_normals = false;
    float m_area = 0.f;
    DiscreteDistribution m_area_distr;
    BoundingBox m_bounds;
};

/// Shared parameters of every shape plugin: bsdf (default diffuse 0.5) and an
/// optional area emitter child; call once the shape object exists.
void attach_shape_children(Shape &shape, const Properties &props);

} // namespace mvpt
