// OBJ files through tinyobjloader, re-indexed so that each distinct
// (position, normal, uv) triple becomes one vertex. Polygons are
// fan-triangulated here ((0,1,2), (0,2,3), ...) as Mitsuba does: tinyobjloader's
// own triangulation may pick other diagonals, which changes non-planar quads.
#include "mesh_data.h"

#include <tiny_obj_loader.h>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string_view>
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
                                    " " + (count == 1 ? std::string(what) : plural(what)));
    }

    /// "vertices", "normals", "texture coordinates".
    static std::string plural(const char *what) {
        return std::string(what) == "vertex" ? "vertices" : std::string(what) + "s";
    }

    const tinyobj::attrib_t &m_attrib;
    const std::filesystem::path &m_path;
    const FileLoc &m_loc;
    MeshData &m_mesh;
    bool m_normals, m_uvs;
    std::map<std::tuple<int, int, int>, uint32_t> m_remap;
};

/// Where the numbers of a `v`, `vn` or `vt` line went wrong, found by check_obj_numbers.
struct ObjBadValues {
    std::vector<size_t> normals, uvs; ///< 0-based indices of those with a number beyond float range
};

/// The value of one number as tinyobjloader reads it, or false when `token` is no number at
/// all (tinyobjloader would read 0 silently); beyond float range gives an infinity.
bool parse_obj_number(std::string_view token, double &value) {
    if (token.starts_with('+')) token.remove_prefix(1);
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (end != token.data() + token.size()) return false;
    if (ec == std::errc::result_out_of_range) value = std::strtod(std::string(token).c_str(), nullptr);
    else if (ec != std::errc()) return false;
    if (std::abs(value) > double(std::numeric_limits<float>::max())) value = std::numeric_limits<double>::infinity();
    return true;
}

/// The numbers of the file's `v`, `vn` and `vt` lines checked before tinyobjloader reads
/// them: a word that is no number, too few coordinates, or a vertex position that is not a
/// finite float is an error at its line; a normal or texture coordinate beyond float range is
/// listed in `bad` (the mesh replaces it and says so).
void check_obj_numbers(const std::string &text, const std::filesystem::path &path, const FileLoc &from,
                       ObjBadValues &bad) {
    const char *space = " \t\r\f\v";
    size_t pos = 0, normals = 0, uvs = 0;
    for (int line = 1; pos < text.size(); ++line) {
        size_t end = std::min(text.find('\n', pos), text.size());
        std::string_view rest(text.data() + pos, end - pos);
        const size_t line_start = pos;
        pos = end + 1;
        rest = rest.substr(0, rest.find('#'));
        auto word = [&]() {
            const size_t b = std::min(rest.find_first_not_of(space), rest.size());
            rest.remove_prefix(b);
            const size_t e = std::min(rest.find_first_of(space), rest.size());
            std::string_view w = rest.substr(0, e);
            rest.remove_prefix(e);
            return w;
        };
        const std::string_view key = word();
        const int kind = key == "v" ? 0 : key == "vn" ? 1 : key == "vt" ? 2 : -1;
        if (kind < 0) continue;
        static const char *what[] = {"a vertex position", "a vertex normal", "a texture coordinate"};
        auto fail = [&](std::string_view at, const std::string &msg) {
            const int col = int(at.data() - (text.data() + line_start)) + 1;
            throw SceneError(FileLoc{path.string(), line, col}, msg + " (in " + what[kind] + "; the mesh of " + from.str() + ")");
        };
        int count = 0;
        bool finite = true;
        for (std::string_view w = word(); !w.empty(); w = word(), ++count) {
            double v;
            if (!parse_obj_number(w, v)) fail(w, "'" + std::string(w) + "' is not a number");
            if (!std::isfinite(v) && kind == 0) fail(w, "'" + std::string(w) + "' is not a finite number in float range");
            finite = finite && std::isfinite(v);
        }
        const int needed = kind == 2 ? 1 : 3;
        if (count < needed)
            fail(key, "'" + std::string(key) + "' needs " + std::to_string(needed) + " numbers, got " + std::to_string(count));
        if (!finite) (kind == 1 ? bad.normals : bad.uvs).push_back(kind == 1 ? normals : uvs);
        normals += kind == 1, uvs += kind == 2;
    }
}

/// The file's text, or a SceneError at `loc`.
std::string read_text(const std::filesystem::path &path, const FileLoc &loc) {
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    if (!f && !f.eof()) throw SceneError(loc, "cannot read OBJ file '" + path.string() + "'");
    return ss.str();
}

} // namespace

MeshData read_obj(const std::filesystem::path &path, const FileLoc &loc) {
    tinyobj::ObjReaderConfig cfg;
    cfg.triangulate = false;
    cfg.vertex_color = false;
    cfg.mtl_search_path = ""; // materials come from the scene file
    const std::string text = read_text(path, loc);
    ObjBadValues bad;
    check_obj_numbers(text, path, loc, bad);
    tinyobj::ObjReader reader;
    if (!reader.ParseFromString(text, "", cfg)) {
        std::string err = reader.Error();
        while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
        throw SceneError(loc, "cannot read OBJ file '" + path.string() + "': " + (err.empty() ? "parse error" : err));
    }
    // Out-of-range values become NaN, so that the mesh finds and reports them (tinyobjloader's are arbitrary).
    tinyobj::attrib_t attrib = reader.GetAttrib();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (size_t i : bad.normals)
        if (3 * i + 2 < attrib.normals.size()) attrib.normals[3 * i] = nan;
    for (size_t i : bad.uvs)
        if (2 * i + 1 < attrib.texcoords.size()) attrib.texcoords[2 * i] = nan;
    MeshData mesh;
    ObjVertices vertices(attrib, path, loc, mesh);
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
