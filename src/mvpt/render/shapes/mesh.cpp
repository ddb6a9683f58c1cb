#include "mesh.h"

#include "../../core/warp.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include "../bsdf.h"
#include "../embree_errors.h"
#include "../light.h"

namespace mvpt {

TriangleMesh::TriangleMesh(MeshData data, const Properties &props, const Transform &to_world, const std::string &what)
    : m_data(std::move(data)) {
    m_flip_normals = props.get_bool("flip_normals", false);
    bool face_normals = props.get_bool("face_normals", false);
    if (face_normals) m_data.normals.clear();
    check_and_transform(props, to_world, what);
    if (m_data.normals.empty() && !face_normals) m_data.normals = compute_vertex_normals(m_data);
    else if (m_issues.bad_normals > 0) replace_bad_normals();
    build_area_table();
    build_face_normals();
    build_constant_frames();
    detect_parallelogram();
    attach_shape_children(*this, props);
    if (emitter && !(m_area > 0.f)) props.fail("", what + ": an emitting mesh needs a non-zero surface area");
}

void TriangleMesh::check_and_transform(const Properties &props, const Transform &to_world, const std::string &what) {
    size_t nv = m_data.positions.size();
    if (m_data.indices.size() % 3 != 0) props.fail("", what + ": index count is not a multiple of 3");
    for (uint32_t i : m_data.indices)
        if (i >= nv) props.fail("", what + ": a face refers to vertex " + std::to_string(i) + " but there are only " + std::to_string(nv));
    if (!m_data.normals.empty() && m_data.normals.size() != nv) props.fail("", what + ": normal count differs from vertex count");
    if (!m_data.uvs.empty() && m_data.uvs.size() != nv) props.fail("", what + ": uv count differs from vertex count");
    for (const MeshAttribute &a : m_data.attributes) {
        const size_t entries = a.per_face() ? m_data.triangle_count() : nv;
        if (a.values.size() != entries * size_t(a.dim))
            props.fail("", what + ": attribute '" + a.name + "' has " + std::to_string(a.values.size()) + " values, not " +
                               std::to_string(entries * size_t(a.dim)));
    }

    for (size_t i = 0; i < nv; ++i) {
        Point3f &p = m_data.positions[i];
        if (!all_finite(p))
            props.fail("", what + ": vertex " + std::to_string(i + 1) + " of " + std::to_string(nv) +
                               " has a position that is not a finite number");
        p = to_world.point(p);
        m_bounds.expand(p);
    }
    for (auto &n : m_data.normals) {
        Normal3f wn = to_world.normal(n);
        float l = norm(wn);
        if (!std::isfinite(l)) {
            ++m_issues.bad_normals;
            n = Normal3f(std::numeric_limits<float>::quiet_NaN()); // marked for replace_bad_normals
        } else {
            n = l > 0.f ? wn / l : Normal3f(0.f);
        }
    }
    for (auto &uv : m_data.uvs)
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) uv = Vec2f(0.f, 0.f), ++m_issues.bad_uvs;
}

void TriangleMesh::replace_bad_normals() {
    const std::vector<Normal3f> computed = compute_vertex_normals(m_data);
    for (size_t i = 0; i < m_data.normals.size(); ++i)
        if (!all_finite(m_data.normals[i])) m_data.normals[i] = computed[i];
}

namespace {

/// "n of m <noun> <verb>", the verb agreeing with n.
std::string n_of(size_t n, size_t of, const char *noun, const char *one, const char *many) {
    return std::to_string(n) + " of " + std::to_string(of) + " " + noun + (n == 1 ? one : many);
}

} // namespace

std::string TriangleMesh::data_warning(const std::string &what) const {
    std::vector<std::string> parts;
    if (m_issues.overflow > 0)
        parts.push_back(n_of(m_issues.overflow, m_data.triangle_count(), "triangles", " has", " have") +
                        " an area beyond float range (is to_world too large?) and cannot be hit");
    if (m_issues.bad_normals > 0)
        parts.push_back(n_of(m_issues.bad_normals, m_data.normals.size(), "vertex normals", " is", " are") +
                        " not finite, computed from the faces instead");
    if (m_issues.bad_uvs > 0)
        parts.push_back(n_of(m_issues.bad_uvs, m_data.uvs.size(), "texture coordinates", " is", " are") +
                        " not finite, set to (0, 0)");
    std::string text;
    for (const std::string &p : parts) text += (text.empty() ? what + ": " : "; ") + p;
    return text;
}

std::string TriangleMesh::data_note(const std::string &what) const {
    if (m_issues.degenerate == 0) return {};
    return what + ": " + n_of(m_issues.degenerate, m_data.triangle_count(), "triangles", " has", " have") +
           " no area (collinear or repeated vertices): they cannot be hit and carry no light";
}

void TriangleMesh::build_area_table() {
    std::vector<float> areas(m_data.triangle_count());
    for (size_t i = 0; i < areas.size(); ++i) {
        const Point3f &p0 = m_data.positions[m_data.indices[3 * i]], &p1 = m_data.positions[m_data.indices[3 * i + 1]],
                      &p2 = m_data.positions[m_data.indices[3 * i + 2]];
        areas[i] = 0.5f * norm(cross(p1 - p0, p2 - p0));
        if (!(areas[i] > 0.f)) areas[i] = 0.f, ++m_issues.degenerate;
        else if (!std::isfinite(areas[i])) areas[i] = 0.f, ++m_issues.overflow;
        m_area += areas[i];
    }
    m_area_distr.build(areas);
    m_inv_area = 1.f / m_area;
}

void TriangleMesh::build_face_normals() {
    m_face_normals.resize(m_data.triangle_count());
    m_flat_vertex_normals.assign(m_data.triangle_count(), 0);
    // Equal to within 1e-6 per component: normals computed for a planar region (angle-weighted
    // sums, renormalised) differ in their last bits, and interpolating them moves the shading
    // normal by less than that (1e-6 rad), far below any visible effect.
    auto near = [](const Normal3f &a, const Normal3f &b) {
        return std::max({std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(a.z - b.z)}) <= 1e-6f;
    };
    for (size_t i = 0; i < m_face_normals.size(); ++i) {
        const uint32_t *idx = &m_data.indices[3 * i];
        const Point3f &p0 = m_data.positions[idx[0]], &p1 = m_data.positions[idx[1]], &p2 = m_data.positions[idx[2]];
        m_face_normals[i] = normalize(cross(p1 - p0, p2 - p0));
        if (!m_data.normals.empty()) {
            const Normal3f &n0 = m_data.normals[idx[0]], &n1 = m_data.normals[idx[1]], &n2 = m_data.normals[idx[2]];
            m_flat_vertex_normals[i] = near(n0, n1) && near(n1, n2) && squared_norm(n0) > 0.f;
        }
    }
}

void TriangleMesh::build_constant_frames() {
    size_t n_flat = 0;
    for (size_t i = 0; i < m_face_normals.size(); ++i) n_flat += m_data.normals.empty() || m_flat_vertex_normals[i];
    if (!(n_flat > 0 && 2 * n_flat >= m_face_normals.size())) return;
    m_const_frames.resize(m_face_normals.size());
    m_has_const_frame.assign(m_face_normals.size(), 0);
    for (size_t i = 0; i < m_const_frames.size(); ++i) {
        if (!m_data.normals.empty() && !m_flat_vertex_normals[i]) continue;
        m_has_const_frame[i] = 1;
        const uint32_t *idx = &m_data.indices[3 * i];
        Normal3f ns = m_data.normals.empty() ? m_face_normals[i] : m_data.normals[idx[0]];
        m_const_frames[i] = shading_frame(idx[0], idx[1], idx[2], m_flip_normals ? -ns : ns);
    }
}

std::vector<Normal3f> compute_vertex_normals(const MeshData &mesh) {
    std::vector<Normal3f> normals(mesh.positions.size(), Normal3f(0.f));
    auto unit_angle = [](Vec3f a, Vec3f b) {
        // Angle between unit vectors, accurate near 0 and pi.
        float d = dot(a, b);
        return d < 0.f ? Pi - 2.f * std::asin(0.5f * norm(a + b)) : 2.f * std::asin(0.5f * norm(b - a));
    };
    for (size_t f = 0; f < mesh.triangle_count(); ++f) {
        const uint32_t *idx = &mesh.indices[3 * f];
        Point3f v[3] = {mesh.positions[idx[0]], mesh.positions[idx[1]], mesh.positions[idx[2]]};
        Normal3f n = cross(v[1] - v[0], v[2] - v[0]);
        float len2 = squared_norm(n);
        if (!(len2 > 0.f)) continue;
        n = n / std::sqrt(len2);
        for (int j = 0; j < 3; ++j) {
            Vec3f e1 = v[(j + 1) % 3] - v[j], e2 = v[(j + 2) % 3] - v[j];
            float l1 = norm(e1), l2 = norm(e2);
            if (l1 > 0.f && l2 > 0.f) normals[idx[j]] += n * unit_angle(e1 / l1, e2 / l2);
        }
    }
    for (auto &n : normals) {
        float l = norm(n);
        n = (l > 0.f && std::isfinite(l)) ? n / l : Normal3f(1.f, 0.f, 0.f);
    }
    return normals;
}

unsigned TriangleMesh::attach(RTCDevice device, RTCScene scene, const MotionTime &) {
    RTCGeometry g = embree_checked(rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE), device, "a mesh");
    struct Release { RTCGeometry g; ~Release() { rtcReleaseGeometry(g); } } owner{g};
    // Embree reads 16 bytes per vertex: pad the buffer by one float.
    auto *v = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                               m_data.positions.size());
    embree_check(device, "a mesh's vertices", m_data.positions.empty() ? g : (void *)v);  // (none: no buffer)
    std::memcpy(v, m_data.positions.data(), m_data.positions.size() * sizeof(Point3f));
    auto *idx = (uint32_t *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t),
                                                    m_data.triangle_count());
    embree_check(device, "a mesh's triangles", m_data.indices.empty() ? g : (void *)idx);
    std::memcpy(idx, m_data.indices.data(), m_data.indices.size() * sizeof(uint32_t));
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(scene, g);
    embree_check(device, "a mesh");
    return id;
}

Normal3f TriangleMesh::shading_normal(uint32_t prim, uint32_t i0, uint32_t i1, uint32_t i2, float b0, Vec2f b,
                                      Normal3f n) const {
    if (m_data.normals.empty()) return n;
    // Stored vertex normals are unit length: a flat triangle's interpolation is its vertex normal.
    if (m_flat_vertex_normals[prim]) return m_data.normals[i0];
    Normal3f s = m_data.normals[i0] * b0 + m_data.normals[i1] * b.x + m_data.normals[i2] * b.y;
    float l2 = squared_norm(s);
    return l2 > 0.f ? s * (1.f / std::sqrt(l2)) : n;
}

void TriangleMesh::fill_interaction(const Ray &, float t, uint32_t prim, Vec2f b, SurfaceInteraction &si) const {
    uint32_t i0 = m_data.indices[3 * prim], i1 = m_data.indices[3 * prim + 1], i2 = m_data.indices[3 * prim + 2];
    const Point3f &p0 = m_data.positions[i0], &p1 = m_data.positions[i1], &p2 = m_data.positions[i2];
    float b0 = 1.f - b.x - b.y;
    si.t = t;
    si.p = p0 * b0 + p1 * b.x + p2 * b.y;
    Normal3f n = m_face_normals[prim];
    si.n = m_flip_normals ? -n : n;
    si.uv = m_data.uvs.empty() ? b : m_data.uvs[i0] * b0 + m_data.uvs[i1] * b.x + m_data.uvs[i2] * b.y;
    if (!m_const_frames.empty() && m_has_const_frame[prim]) {
        si.sh_frame = m_const_frames[prim];
        return;
    }
    Normal3f ns = shading_normal(prim, i0, i1, i2, b0, b, n);
    si.sh_frame = shading_frame(i0, i1, i2, m_flip_normals ? -ns : ns);
}

Frame TriangleMesh::shading_frame(uint32_t i0, uint32_t i1, uint32_t i2, Normal3f ns) const {
    if (m_data.uvs.empty()) return Frame(ns);
    Vec2f uv0 = m_data.uvs[i0], uv1 = m_data.uvs[i1], uv2 = m_data.uvs[i2];
    Vec2f duv0 = uv1 - uv0, duv1 = uv2 - uv0;
    float det = duv0.x * duv1.y - duv0.y * duv1.x;
    if (det != 0.f) {
        const Point3f &p0 = m_data.positions[i0], &p1 = m_data.positions[i1], &p2 = m_data.positions[i2];
        Vec3f dp0 = p1 - p0, dp1 = p2 - p0;
        float inv = 1.f / det;
        Vec3f dp_du = (dp0 * duv1.y - dp1 * duv0.y) * inv;
        // Shading frame from dp/du projected onto the tangent plane (Mitsuba's initialize_sh_frame).
        if (all_finite(dp_du) && squared_norm(dp_du) > 0.f) {
            Vec3f s = dp_du - ns * dot(ns, dp_du);
            float l = norm(s);
            if (l > 1e-12f) {
                s = s / l;
                return Frame(s, cross(ns, s), ns);
            }
        }
    }
    return Frame(ns);
}

std::pair<Vec3f, Vec3f> TriangleMesh::uv_partials(uint32_t prim, Point3f) const {
    const uint32_t *idx = &m_data.indices[3 * size_t(prim)];
    const Point3f &p0 = m_data.positions[idx[0]];
    const Vec3f e1 = m_data.positions[idx[1]] - p0, e2 = m_data.positions[idx[2]] - p0;
    if (m_data.uvs.empty()) return {e1, e2}; // barycentric: u = b1, v = b2
    // The change from barycentric to texture coordinates (zero where the uvs are degenerate).
    const Vec2f uv0 = m_data.uvs[idx[0]], duv0 = m_data.uvs[idx[1]] - uv0, duv1 = m_data.uvs[idx[2]] - uv0;
    const float det = duv0.x * duv1.y - duv0.y * duv1.x, inv = det != 0.f ? 1.f / det : 0.f;
    return {(e1 * duv1.y - e2 * duv0.y) * inv, (e2 * duv0.x - e1 * duv1.x) * inv};
}

std::vector<std::string> TriangleMesh::attribute_names() const {
    std::vector<std::string> names;
    for (const MeshAttribute &a : m_data.attributes) names.push_back(a.name);
    return names;
}

Color3f TriangleMesh::eval_attribute(const std::string &name, const SurfaceInteraction &si) const {
    for (const MeshAttribute &a : m_data.attributes) {
        if (a.name != name) continue;
        const auto entry = [&](size_t i) {
            const float *v = &a.values[i * size_t(a.dim)];
            return a.dim == 3 ? Color3f(v[0], v[1], v[2]) : Color3f(v[0]);
        };
        if (a.per_face()) return entry(si.prim);
        const uint32_t *idx = &m_data.indices[3 * size_t(si.prim)];
        const Vec2f b = si.prim_uv;
        return entry(idx[0]) * (1.f - b.x - b.y) + entry(idx[1]) * b.x + entry(idx[2]) * b.y;
    }
    return Color3f(0.f);
}

ShapeSample TriangleMesh::sample_area(Vec2f u) const {
    ShapeSample s;
    sample_point(u, s);
    return s;
}

std::pair<ShapeSample, float> TriangleMesh::sample_solid_angle(Point3f ref, Vec2f u) const {
    std::pair<ShapeSample, float> result;
    ShapeSample &s = result.first;
    sample_point(u, s);
    result.second = area_to_solid_angle(s.pdf_a, ref, s.p, s.n);
    return result;
}

void TriangleMesh::detect_parallelogram() {
    if (m_data.triangle_count() != 2 || m_const_frames.empty() || !m_has_const_frame[0] || !m_has_const_frame[1] ||
        !(m_const_frames[0].n == m_const_frames[1].n))
        return;
    const uint32_t *a = &m_data.indices[0], *b = &m_data.indices[3];
    // The vertex of each triangle that the other lacks; the two shared ones form the diagonal.
    auto in = [&](const uint32_t *t, uint32_t i) {
        const Point3f &p = m_data.positions[i];
        return p == m_data.positions[t[0]] || p == m_data.positions[t[1]] || p == m_data.positions[t[2]];
    };
    int only_a = -1, only_b = -1, shared = 0;
    for (int k = 0; k < 3; ++k) {
        if (in(b, a[k])) ++shared;
        else only_a = k;
        if (!in(a, b[k])) only_b = k;
    }
    if (shared != 2 || only_a < 0 || only_b < 0) return;
    const Point3f &pa = m_data.positions[a[only_a]], &pb = m_data.positions[b[only_b]];
    const Point3f &s1 = m_data.positions[a[(only_a + 1) % 3]], &s2 = m_data.positions[a[(only_a + 2) % 3]];
    // A parallelogram's diagonals bisect each other: pa + pb = s1 + s2 (to float rounding).
    Vec3f gap = (pa + pb) - (s1 + s2);
    float scale = std::max({std::abs(pa.x), std::abs(pa.y), std::abs(pa.z), std::abs(pb.x), std::abs(pb.y), std::abs(pb.z),
                            std::abs(s1.x), std::abs(s1.y), std::abs(s1.z), std::abs(s2.x), std::abs(s2.y), std::abs(s2.z)});
    if (!(std::max({std::abs(gap.x), std::abs(gap.y), std::abs(gap.z)}) <= 1e-6f * scale)) return;
    m_is_parallelogram = true;
    m_quad_origin = pa;
    m_quad_e1 = s1 - pa;
    m_quad_e2 = s2 - pa;
    m_quad_normal = m_const_frames[0].n;
}

void TriangleMesh::sample_point(Vec2f u, ShapeSample &s) const {
    if (m_is_parallelogram && !sample_uv) {
        s.p = m_quad_origin + m_quad_e1 * u.x + m_quad_e2 * u.y;
        s.n = m_quad_normal;
        s.pdf_a = m_inv_area;
        return;
    }
    float pmf, ux;
    size_t tri = m_area_distr.sample(u.x, &pmf, &ux);
    Vec2f b = warp::square_to_uniform_triangle({ux, u.y});
    uint32_t i0 = m_data.indices[3 * tri], i1 = m_data.indices[3 * tri + 1], i2 = m_data.indices[3 * tri + 2];
    const Point3f &p0 = m_data.positions[i0], &p1 = m_data.positions[i1], &p2 = m_data.positions[i2];
    float b0 = 1.f - b.x - b.y;
    s.p = p0 * b0 + p1 * b.x + p2 * b.y;
    // Smooth meshes: the interpolated normal, as Mitsuba uses for emitter sampling.
    if (!m_const_frames.empty() && m_has_const_frame[tri]) {
        s.n = m_const_frames[tri].n;
    } else {
        Normal3f n = shading_normal(uint32_t(tri), i0, i1, i2, b0, b, m_face_normals[tri]);
        s.n = m_flip_normals ? -n : n;
    }
    if (!m_data.uvs.empty())
        s.uv = m_data.uvs[i0] * b0 + m_data.uvs[i1] * b.x + m_data.uvs[i2] * b.y;
    else
        s.uv = b;
    s.pdf_a = m_inv_area;
}

} // namespace mvpt
