// Triangle meshes (obj, ply, serialized, rectangle, cube): world-space
// vertices in an Embree triangle geometry.
#pragma once

#include "../../core/distribution.h"
#include "../../io/mesh_data.h"
#include "../../core/plugin.h"
#include "../shape.h"

namespace mvpt {

class TriangleMesh : public Shape {
public:
    /// Takes `data` in object space; applies `to_world` and flip_normals /
    /// face_normals from `props`, computes vertex normals when the data has none
    /// (as Mitsuba does), and validates the data (errors at `props`' location).
    TriangleMesh(MeshData data, const Properties &props, const Transform &to_world, const std::string &what);

    unsigned attach(RTCDevice device, RTCScene scene, const MotionTime &motion) override;
    void fill_interaction(const Ray &ray, float t, uint32_t prim, Vec2f b, SurfaceInteraction &si) const override;
    float area() const override { return m_area; }
    BoundingBox bounds() const override { return m_bounds; }
    ShapeSample sample_area(Vec2f u) const override;
    /// Area sampling converted to solid angle, as Shape's default, without the extra call and copy.
    std::pair<ShapeSample, float> sample_solid_angle(Point3f ref, Vec2f u) const override;
    /// Constant over a triangle: from its edges and uvs (barycentric without uvs).
    std::pair<Vec3f, Vec3f> uv_partials(uint32_t prim, Point3f p) const override;

    std::vector<std::string> attribute_names() const override;
    /// Interpolated over the triangle with the hit's barycentrics (vertex_), or the triangle's (face_).
    Color3f eval_attribute(const std::string &name, const SurfaceInteraction &si) const override;

    const MeshData &data() const { return m_data; }
    /// What the mesh lost or had replaced (triangles whose area overflows, non-finite normals
    /// or uvs), in one sentence that starts with `what`; empty when nothing.
    std::string data_warning(const std::string &what) const;
    /// Its triangles of zero area, harmless (nothing to hit, no light) and common in exported
    /// meshes, as a note; empty when none.
    std::string data_note(const std::string &what) const;
    /// True, with the parallelogram and its area density, when sample_area maps u to
    /// origin + u.x e1 + u.y e2 with the constant normal n (see m_is_parallelogram).
    bool parallelogram(Point3f &origin, Vec3f &e1, Vec3f &e2, Normal3f &n, float &inv_area) const {
        if (!m_is_parallelogram || sample_uv) return false;
        origin = m_quad_origin, e1 = m_quad_e1, e2 = m_quad_e2, n = m_quad_normal, inv_area = m_inv_area;
        return true;
    }

private:
    /// Unit face normal of triangle `prim` (before flip_normals).
    const Normal3f &face_normal(uint32_t prim) const { return m_face_normals[prim]; }
    /// Shading normal at barycentrics (b0, b.x, b.y) before flip_normals, falling back to `n`.
    Normal3f shading_normal(uint32_t prim, uint32_t i0, uint32_t i1, uint32_t i2, float b0, Vec2f b, Normal3f n) const;
    /// Shading frame around the (flipped) shading normal `ns`, aligned with dp/du when the mesh has uvs.
    Frame shading_frame(uint32_t i0, uint32_t i1, uint32_t i2, Normal3f ns) const;
    /// `sample_area` into `s`.
    void sample_point(Vec2f u, ShapeSample &s) const;

    MeshData m_data;
    /// Counts for data_warning and data_note: triangles of zero or overflowing area, vertex
    /// normals and texture coordinates that were not finite.
    struct DataIssues {
        size_t degenerate = 0, overflow = 0, bad_normals = 0, bad_uvs = 0;
    } m_issues;
    bool m_flip_normals = false;
    float m_area = 0.f, m_inv_area = 0.f;
    /// Per-triangle precomputed data (hit and emitter sampling are per-path hot spots).
    std::vector<Normal3f> m_face_normals;
    /// Per triangle: its three vertex normals agree to within 1e-6 and are non-zero, so
    /// interpolation and renormalisation reduce to the first one.
    std::vector<uint8_t> m_flat_vertex_normals;
    /// Shading frames of the triangles whose frame is constant over them (face normals, or
    /// flat vertex normals), flip_normals applied, so that their hits and emitter samples
    /// skip normal interpolation and frame construction; `m_has_const_frame` marks them.
    /// Empty when fewer than half of the triangles have one.
    std::vector<Frame> m_const_frames;
    std::vector<uint8_t> m_has_const_frame;
    DiscreteDistribution m_area_distr;
    BoundingBox m_bounds;
    /// Two flat triangles forming a parallelogram (a rectangle or quad emitter): when no uv
    /// is needed, `sample_point` maps u to m_quad_origin + u.x m_quad_e1 + u.y m_quad_e2
    /// (uniform by area, as the triangle choice and triangle warp give) with the constant
    /// normal m_quad_normal.
    bool m_is_parallelogram = false;
    Point3f m_quad_origin;
    Vec3f m_quad_e1, m_quad_e2;
    Normal3f m_quad_normal;
    /// Sets the members above when the mesh is such a parallelogram.
    void detect_parallelogram();
    /// The file's counts and indices checked, positions and normals into world space
    /// (non-finite normals marked NaN, non-finite uvs zeroed, both counted in m_issues).
    void check_and_transform(const Properties &props, const Transform &to_world, const std::string &what);
    /// Vertex normals marked by check_and_transform, replaced by the faces' (compute_vertex_normals).
    void replace_bad_normals();
    /// The triangles' areas, the total and the distribution that picks a triangle by area.
    void build_area_table();
    /// Face normals, and which triangles' vertex normals are all equal (flat).
    void build_face_normals();
    /// The shading frames of flat triangles, kept when at least half of them are.
    void build_constant_frames();
};

/// Shared parameters of every shape plugin: bsdf (default diffuse 0.5) and an
/// optional area emitter child; call once the shape object exists.
void attach_shape_children(Shape &shape, const Properties &props);

/// Angle-weighted vertex normals [Thürmer & Wüthrich 1998], Mitsuba's
/// `recompute_vertex_normals`; vertices without a valid face get (1, 0, 0).
std::vector<Normal3f> compute_vertex_normals(const MeshData &mesh);

} // namespace mvpt
