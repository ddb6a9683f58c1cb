// OBJ files through tinyobjloader, re-indexed so that each distinct
// (position, normal, uv) triple becomes one vertex. Polygons are
// fan-triangulated here ((0,1,2), (0,2,3), ...) as Mitsuba does: tinyobjloader's
// own triangulation may pick other diagonals, which changes non-planar quads.
#include "mesh_data.h"

#include <tiny_obj_loader.h>

#include <map>
#include <tuple>

namespace mvpt {

namespace {

/// The mesh's vertices, one per distinct (position, normal, uv) index triple of the file.
class ObjVertices {
public:
    ObjVertices(const tinyobj::attrib_t &attrib, const std::filesystem::path &path, const FileLoc &loc, MeshData &mesh)
        : m_attrib(attrib), m_path(path), m_loc(loc), m_mesh(mesh), m_normals(!attrib.normals.empty()),
          m_uvs(!attrib.texcoords.empty()) {}

    /// The vertex of a face corner, made at its first use; `face` (1-based) for messages.
    uint32_t of(const tinyobj::index_t &idx, size_t face) {
        check(idx.vertex_index, m_attrib.vertices.size() / 3, "vertex", false, face);
        check(idx.normal_index, m_attrib.normals.size() / 3, "normal", true, face);
        check(idx.texcoord_index, m_attrib.texcoords.size() / 2, "texture coordinate", true, face);
        auto key = std::make_tuple(idx.vertex_index, m_normals ? idx.normal_index : -1, m_uvs ? idx.texcoord_index : -1);
        auto it = m_remap.find(key);
        if (it != m_remap.end()) return it->second;
        const uint32_t id = uint32_t(m_mesh.positions.size());
        const float *v = &m_attrib.vertices[3 * size_t(idx.vertex_index)];
        m_mesh.positions.push_back({v[0], v[1], v[2]});
        if (m_normals) {
            Normal3f n(0.f);
            if (idx.normal_index >= 0) {
                const float *nn = &m_attrib.normals[3 * size_t(idx.normal_index)];
                n = {nn[0], nn[1], nn[2]};
            }
            m_mesh.normals.push_back(n);
        }
        if (m_uvs) {
            Vec2f uv(0.f, 0.f);
            if (idx.texcoord_index >= 0) {
                const float *t = &m_attrib.texcoords[2 * size_t(idx.texcoord_index)];
                uv = {t[0], t[1]};
            }
            m_mesh.uvs.push_back(uv);
        }
        m_remap.emplace(key, id);
        return id;
    }

private:
    /// An index into `count` values: in range, or -1 where the face gives none (`optional`).
    void check(int index, size_t count, const char *what, bool optional, size_t face) const {
        if ((optional && index == -1) || (index >= 0 && size_t(index) < count)) return;
        const long long shown = index >= 0 ? index + 1LL : index; // as written (1-based), or the resolved relative index
        throw SceneError(m_loc, "OBJ file '" + m_path.string() + "': face " + std::to_string(face) + " uses " + what +
                                    " index " + std::to_string(shown) + " but the file has " + std::to_string(count) +
                                    " " + what + (count == 1 ? "" : "s"));
    }

    const tinyobj::attrib_t &m_attrib;
    const std::filesystem::path &m_path;
    const FileLoc &m_loc;
    MeshData &m_mesh;
    bool m_normals, m_uvs;
    std::map<std::tuple<int, int, int>, uint32_t> m_remap;
};

} // namespace

MeshData read_obj(const std::filesystem::path &path, const FileLoc &loc) {
    tinyobj::ObjReaderConfig cfg;
    cfg.triangulate = false;
    cfg.vertex_color = false;
    cfg.mtl_search_path = ""; // materials come from the scene file
    tinyobj::ObjReader reader;
    if (!reader.ParseFromFile(path.string(), cfg)) {
        std::string err = reader.Error();
        while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
        throw SceneError(loc, "cannot read OBJ file '" + path.string() + "': " + (err.empty() ? "parse error" : err));
    }
    MeshData mesh;
    ObjVertices vertices(reader.GetAttrib(), path, loc, mesh);
    size_t face = 0; // 1-based, counted over the file's faces, for messages
    std::vector<uint32_t> poly;
    for (const auto &shape : reader.GetShapes()) {
        size_t next = 0;
        for (unsigned nfv : shape.mesh.num_face_vertices) {
            ++face;
            poly.clear();
            for (size_t k = 0; k < nfv && next < shape.mesh.indices.size(); ++k)
                poly.push_back(vertices.of(shape.mesh.indices[next++], face));
            for (size_t k = 2; k < poly.size(); ++k)
                mesh.indices.insert(mesh.indices.end(), {poly[0], poly[k - 1], poly[k]});
        }
    }
    if (mesh.indices.empty()) throw SceneError(loc, "OBJ file '" + path.string() + "' contains no faces");
    return mesh;
}

} // namespace mvpt
