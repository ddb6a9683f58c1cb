// OBJ files through tinyobjloader, re-indexed so that each distinct
// (position, normal, uv) triple becomes one vertex. Polygons are
// fan-triangulated here ((0,1,2), (0,2,3), ...) as Mitsuba does: tinyobjloader's
// own triangulation may pick other diagonals, which changes non-planar quads.
#include "mesh_data.h"

#include <tiny_obj_loader.h>

#include <map>
#include <tuple>

namespace mvpt {

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
    const auto &attrib = reader.GetAttrib();
    MeshData mesh;
    std::map<std::tuple<int, int, int>, uint32_t> remap;
    bool any_normals = !attrib.normals.empty(), any_uvs = !attrib.texcoords.empty();
    const size_t nv = attrib.vertices.size() / 3, nn = attrib.normals.size() / 3, nt = attrib.texcoords.size() / 2;
    size_t face = 0; // 1-based, counted over the file's faces, for messages
    // An index into `count` values: in range, or -1 where the face gives none (not for positions).
    auto check = [&](int index, size_t count, const char *what, bool optional) {
        if ((optional && index == -1) || (index >= 0 && size_t(index) < count)) return;
        const long long shown = index >= 0 ? index + 1LL : index; // as written (1-based), or the resolved relative index
        throw SceneError(loc, "OBJ file '" + path.string() + "': face " + std::to_string(face) + " uses " + what +
                                  " index " + std::to_string(shown) + " but the file has " + std::to_string(count) + " " +
                                  what + (count == 1 ? "" : "s"));
    };
    // One vertex per distinct (position, normal, uv) index triple.
    auto vertex_of = [&](const tinyobj::index_t &idx) {
        check(idx.vertex_index, nv, "vertex", false);
        check(idx.normal_index, nn, "normal", true);
        check(idx.texcoord_index, nt, "texture coordinate", true);
        auto key = std::make_tuple(idx.vertex_index, any_normals ? idx.normal_index : -1, any_uvs ? idx.texcoord_index : -1);
        auto it = remap.find(key);
        if (it != remap.end()) return it->second;
        uint32_t id = uint32_t(mesh.positions.size());
        const float *v = &attrib.vertices[3 * size_t(idx.vertex_index)];
        mesh.positions.push_back({v[0], v[1], v[2]});
        if (any_normals) {
            Normal3f n(0.f);
            if (idx.normal_index >= 0) {
                const float *nn = &attrib.normals[3 * size_t(idx.normal_index)];
                n = {nn[0], nn[1], nn[2]};
            }
            mesh.normals.push_back(n);
        }
        if (any_uvs) {
            Vec2f uv(0.f, 0.f);
            if (idx.texcoord_index >= 0) {
                const float *t = &attrib.texcoords[2 * size_t(idx.texcoord_index)];
                uv = {t[0], t[1]};
            }
            mesh.uvs.push_back(uv);
        }
        remap.emplace(key, id);
        return id;
    };
    std::vector<uint32_t> poly;
    for (const auto &shape : reader.GetShapes()) {
        size_t next = 0;
        for (unsigned nfv : shape.mesh.num_face_vertices) {
            ++face;
            poly.clear();
            for (size_t k = 0; k < nfv && next < shape.mesh.indices.size(); ++k)
                poly.push_back(vertex_of(shape.mesh.indices[next++]));
            for (size_t k = 2; k < poly.size(); ++k)
                mesh.indices.insert(mesh.indices.end(), {poly[0], poly[k - 1], poly[k]});
        }
    }
    if (mesh.indices.empty()) throw SceneError(loc, "OBJ file '" + path.string() + "' contains no faces");
    return mesh;
}

} // namespace mvpt
