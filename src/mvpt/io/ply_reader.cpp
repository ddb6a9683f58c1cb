// Stanford PLY meshes: ASCII, binary_little_endian and binary_big_endian.
// Reads positions, normals, uvs, polygon faces (fan-triangulated) and the vertices' and
// faces' mesh attributes (ply_attributes.h); every other element and property is skipped. All counts are checked against the
// bytes that remain, so a truncated or corrupt file fails cleanly.
#include "mesh_data.h"
#include "ply_attributes.h"

#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace mvpt {

namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

size_t type_size(PlyType t) {
    switch (t) {
        case PlyType::Int8: case PlyType::UInt8: return 1;
        case PlyType::Int16: case PlyType::UInt16: return 2;
        case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
        default: return 8;
    }
}

bool parse_type(const std::string &s, PlyType &t) {
    static const std::pair<const char *, PlyType> names[] = {
        {"char", PlyType::Int8},     {"int8", PlyType::Int8},     {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},   {"short", PlyType::Int16},   {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16}, {"int", PlyType::Int32},
        {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},   {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64}};
    for (auto &[n, v] : names)
        if (s == n) { t = v; return true; }
    return false;
}

bool is_integer(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32;
    bool is_list = false;
    PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> props;
};

enum class PlyFormat { Ascii, BinaryLE, BinaryBE };

/// Sequential access to the body of the file (binary or ASCII tokens), with
/// errors that name the file.
class PlyBody {
public:
    PlyBody(const std::string &data, size_t pos, PlyFormat fmt, const std::string &file, const FileLoc &loc)
        : m_data(data), m_pos(pos), m_fmt(fmt), m_file(file), m_loc(loc) {}

    size_t remaining() const { return m_data.size() - m_pos; }

    [[noreturn]] void fail(const std::string &msg) const {
        throw SceneError(m_loc, "PLY file '" + m_file + "': " + msg);
    }

    double read(PlyType t, const char *what) {
        if (m_fmt == PlyFormat::Ascii) return read_ascii(t, what);
        size_t n = type_size(t);
        if (remaining() < n) fail(std::string("file is truncated (while reading ") + what + ")");
        unsigned char b[8];
        std::memcpy(b, m_data.data() + m_pos, n);
        m_pos += n;
        bool swap = (m_fmt == PlyFormat::BinaryBE) != (std::endian::native == std::endian::big);
        if (swap)
            for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
        switch (t) {
            case PlyType::Int8: { int8_t v; std::memcpy(&v, b, 1); return v; }
            case PlyType::UInt8: return b[0];
            case PlyType::Int16: { int16_t v; std::memcpy(&v, b, 2); return v; }
            case PlyType::UInt16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
            case PlyType::Int32: { int32_t v; std::memcpy(&v, b, 4); return v; }
            case PlyType::UInt32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
            case PlyType::Float32: { float v; std::memcpy(&v, b, 4); return v; }
            default: { double v; std::memcpy(&v, b, 8); return v; }
        }
    }

    /// Skip `n` values of type `t` without converting them.
    void skip(PlyType t, uint64_t n, const char *what) {
        if (m_fmt != PlyFormat::Ascii) {
            if (n > remaining() / type_size(t)) fail(std::string("file is truncated (while skipping ") + what + ")");
            m_pos += size_t(n) * type_size(t);
            return;
        }
        for (uint64_t i = 0; i < n; ++i) read_ascii(t, what);
    }

    /// Minimum bytes one value occupies (ASCII: a digit and a separator).
    size_t min_bytes(PlyType t) const { return m_fmt == PlyFormat::Ascii ? 1 : type_size(t); }

private:
    double read_ascii(PlyType t, const char *what) {
        while (m_pos < m_data.size() && std::isspace((unsigned char)m_data[m_pos])) ++m_pos;
        if (m_pos >= m_data.size()) fail(std::string("file is truncated (while reading ") + what + ")");
        const char *b = m_data.data() + m_pos, *e = m_data.data() + m_data.size();
        double v = 0;
        auto [ptr, ec] = std::from_chars(b, e, v);
        if (ec != std::errc() || (ptr < e && !std::isspace((unsigned char)*ptr))) {
            size_t len = 0;
            while (b + len < e && len < 20 && !std::isspace((unsigned char)b[len])) ++len;
            fail(std::string("expected a number for ") + what + ", got '" + std::string(b, len) + "'");
        }
        if (is_integer(t) && v != std::floor(v)) fail(std::string("expected an integer for ") + what);
        m_pos = size_t(ptr - m_data.data());
        return v;
    }

    const std::string &m_data;
    size_t m_pos;
    PlyFormat m_fmt;
    const std::string &m_file;
    const FileLoc &m_loc;
};

/// A property line of the header after its keyword: a list or a scalar property.
template <typename Fail> PlyProperty read_property(std::istringstream &ls, const std::string &line, Fail &&fail) {
    PlyProperty prop;
    std::string t;
    ls >> t;
    if (t == "list") {
        std::string ct, it;
        ls >> ct >> it >> prop.name;
        prop.is_list = true;
        if (!parse_type(ct, prop.count_type) || !is_integer(prop.count_type) || !parse_type(it, prop.type))
            fail("malformed list property '" + line + "'");
    } else {
        ls >> prop.name;
        if (!parse_type(t, prop.type)) fail("unknown property type '" + t + "'");
    }
    if (prop.name.empty()) fail("property without a name: '" + line + "'");
    return prop;
}

/// The header: the body's format and its elements (`pos` is left at the body's first byte).
struct PlyHeader {
    PlyFormat format = PlyFormat::Ascii;
    std::vector<PlyElement> elements;
};

template <typename Fail> PlyHeader read_header(const std::string &data, size_t &pos, Fail &&fail) {
    auto next_line = [&](std::string &line) {
        if (pos >= data.size()) return false;
        size_t e = data.find('\n', pos);
        if (e == std::string::npos) e = data.size();
        line = data.substr(pos, e - pos);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        pos = std::min(e + 1, data.size());
        return true;
    };
    std::string line;
    if (!next_line(line) || line != "ply") fail("not a PLY file (missing 'ply' magic line)");
    PlyHeader h;
    bool have_format = false, have_end = false;
    while (!have_end && next_line(line)) {
        std::istringstream ls(line);
        std::string kw;
        ls >> kw;
        if (kw.empty() || kw == "comment" || kw == "obj_info") continue;
        if (kw == "end_header") {
            have_end = true;
        } else if (kw == "format") {
            std::string f, ver;
            ls >> f >> ver;
            if (f == "ascii") h.format = PlyFormat::Ascii;
            else if (f == "binary_little_endian") h.format = PlyFormat::BinaryLE;
            else if (f == "binary_big_endian") h.format = PlyFormat::BinaryBE;
            else fail("unknown format '" + f + "'");
            have_format = true;
        } else if (kw == "element") {
            PlyElement el;
            std::string count;
            ls >> el.name >> count;
            auto [p, ec] = std::from_chars(count.data(), count.data() + count.size(), el.count);
            if (el.name.empty() || ec != std::errc() || p != count.data() + count.size())
                fail("malformed element line '" + line + "'");
            h.elements.push_back(el);
        } else if (kw == "property") {
            if (h.elements.empty()) fail("'property' before any 'element' in the header");
            h.elements.back().props.push_back(read_property(ls, line, fail));
        } else {
            fail("unexpected header line '" + line + "'");
        }
    }
    if (!have_end) fail("the header has no 'end_header' line");
    if (!have_format) fail("the header has no 'format' line");
    return h;
}

/// The largest value of an integer type (0 for floating-point types).
double integer_max(PlyType t) {
    switch (t) {
        case PlyType::Int8: return 127.0;
        case PlyType::UInt8: return 255.0;
        case PlyType::Int16: return 32767.0;
        case PlyType::UInt16: return 65535.0;
        case PlyType::Int32: return 2147483647.0;
        case PlyType::UInt32: return 4294967295.0;
        default: return 0.0;
    }
}

/// The element's mesh attributes (ply_attributes.h) among its scalar properties that are not
/// `reserved`: their layouts, and for each attribute channel the property that holds it.
struct ElementAttributes {
    std::vector<PlyAttributeLayout> layouts;
    /// Per property of the element: its index among the candidate fields, or -1.
    std::vector<int> field_of;
};

ElementAttributes element_attributes(const PlyElement &el, const std::vector<int> &reserved, const std::string &prefix) {
    ElementAttributes ea;
    std::vector<PlyField> fields;
    ea.field_of.assign(el.props.size(), -1);
    for (size_t i = 0; i < el.props.size(); ++i)
        if (!el.props[i].is_list && reserved[i] < 0) {
            ea.field_of[i] = int(fields.size());
            fields.push_back({el.props[i].name, integer_max(el.props[i].type)});
        }
    ea.layouts = ply_attribute_layout(fields, prefix);
    return ea;
}

/// Appends one entry of each attribute from the candidate fields' values `row`, `copies` times.
void append_attributes(const ElementAttributes &ea, const std::vector<double> &row, size_t copies, MeshData &mesh,
                       size_t first) {
    for (size_t a = 0; a < ea.layouts.size(); ++a) {
        const PlyAttributeLayout &l = ea.layouts[a];
        std::vector<float> &v = mesh.attributes[first + a].values;
        for (size_t k = 0; k < copies; ++k)
            for (size_t c = 0; c < l.fields.size(); ++c) v.push_back(float(row[l.fields[c]]) * l.scale[c]);
    }
}

/// Adds an empty attribute to `mesh` per layout of `ea`; returns the index of the first.
size_t add_attributes(const ElementAttributes &ea, MeshData &mesh) {
    const size_t first = mesh.attributes.size();
    for (const PlyAttributeLayout &l : ea.layouts) mesh.attributes.push_back({l.name, int(l.fields.size()), {}});
    return first;
}

/// The vertex element: positions, normals and uvs where it has all their properties, and
/// its mesh attributes.
void read_vertices(PlyBody &body, const PlyElement &el, MeshData &mesh) {
    // Property slots: 0-2 position, 3-5 normal, 6-7 uv.
    std::vector<int> slot(el.props.size(), -1);
    for (size_t i = 0; i < el.props.size(); ++i) {
        const std::string &n = el.props[i].name;
        static const char *names[8][3] = {{"x"}, {"y"}, {"z"}, {"nx"}, {"ny"}, {"nz"},
                                          {"u", "s", "texture_u"}, {"v", "t", "texture_v"}};
        for (int s = 0; s < 8; ++s)
            for (const char *alias : names[s])
                if (alias && n == alias && !el.props[i].is_list) slot[i] = s;
    }
    bool has[8] = {};
    for (int s : slot)
        if (s >= 0) has[s] = true;
    if (!has[0] || !has[1] || !has[2]) body.fail("the vertex element lacks x, y or z");
    const bool normals = has[3] && has[4] && has[5], uvs = has[6] && has[7];
    const ElementAttributes ea = element_attributes(el, slot, "vertex_");
    const size_t first = add_attributes(ea, mesh);
    std::vector<double> row(el.props.size());
    mesh.positions.resize(size_t(el.count));
    if (normals) mesh.normals.resize(size_t(el.count));
    if (uvs) mesh.uvs.resize(size_t(el.count));
    for (size_t v = 0; v < el.count; ++v) {
        float val[8] = {};
        for (size_t i = 0; i < el.props.size(); ++i) {
            const PlyProperty &p = el.props[i];
            if (p.is_list) {
                double n = body.read(p.count_type, "a list length");
                if (n < 0) body.fail("negative list length in element 'vertex'");
                body.skip(p.type, uint64_t(n), p.name.c_str());
            } else if (slot[i] >= 0) {
                val[slot[i]] = float(body.read(p.type, p.name.c_str()));
            } else if (ea.field_of[i] >= 0) {
                row[size_t(ea.field_of[i])] = body.read(p.type, p.name.c_str());
            } else {
                body.skip(p.type, 1, p.name.c_str());
            }
        }
        mesh.positions[v] = {val[0], val[1], val[2]};
        if (normals) mesh.normals[v] = {val[3], val[4], val[5]};
        if (uvs) mesh.uvs[v] = {val[6], val[7]};
        append_attributes(ea, row, 1, mesh, first);
    }
}

/// The face element's vertex index lists, fan-triangulated (convex polygons), and its mesh
/// attributes, one entry per triangle.
void read_faces(PlyBody &body, const PlyElement &el, MeshData &mesh) {
    int index_prop = -1;
    for (size_t i = 0; i < el.props.size(); ++i)
        if (el.props[i].is_list && (el.props[i].name == "vertex_indices" || el.props[i].name == "vertex_index"))
            index_prop = int(i);
    if (index_prop < 0) body.fail("the face element has no 'vertex_indices' list");
    if (!is_integer(el.props[size_t(index_prop)].type)) body.fail("face vertex indices must be integers");
    const ElementAttributes ea = element_attributes(el, std::vector<int>(el.props.size(), -1), "face_");
    const size_t first = add_attributes(ea, mesh);
    std::vector<double> row(el.props.size());
    std::vector<uint32_t> poly;
    for (size_t f = 0; f < el.count; ++f) {
        size_t triangles = 0;
        for (size_t i = 0; i < el.props.size(); ++i) {
            const PlyProperty &p = el.props[i];
            if (!p.is_list) {
                if (ea.field_of[i] >= 0) row[size_t(ea.field_of[i])] = body.read(p.type, p.name.c_str());
                else body.skip(p.type, 1, p.name.c_str());
                continue;
            }
            double n = body.read(p.count_type, "a list length");
            if (n < 0) body.fail("negative list length in element 'face'");
            if (int(i) != index_prop) { body.skip(p.type, uint64_t(n), p.name.c_str()); continue; }
            if (uint64_t(n) > body.remaining() / body.min_bytes(p.type))
                body.fail("a face declares " + std::to_string(uint64_t(n)) + " vertices, more than the file can hold (truncated or corrupt)");
            poly.resize(size_t(n));
            for (auto &idx : poly) {
                double d = body.read(p.type, "a vertex index");
                if (d < 0 || d > double(UINT32_MAX)) body.fail("invalid vertex index " + std::to_string(int64_t(d)));
                idx = uint32_t(d);
            }
            for (size_t k = 2; k < poly.size(); ++k) mesh.indices.insert(mesh.indices.end(), {poly[0], poly[k - 1], poly[k]});
            triangles = poly.size() >= 3 ? poly.size() - 2 : 0;
        }
        append_attributes(ea, row, triangles, mesh, first);
    }
}

/// Any other element, skipped value by value.
void skip_element(PlyBody &body, const PlyElement &el) {
    for (size_t e = 0; e < el.count; ++e)
        for (const PlyProperty &p : el.props) {
            if (!p.is_list) { body.skip(p.type, 1, p.name.c_str()); continue; }
            double n = body.read(p.count_type, "a list length");
            if (n < 0) body.fail("negative list length in element '" + el.name + "'");
            body.skip(p.type, uint64_t(n), p.name.c_str());
        }
}

} // namespace

MeshData read_ply(const std::filesystem::path &path, const FileLoc &loc) {
    const std::string file = path.string();
    auto fail = [&](const std::string &msg) -> void { throw SceneError(loc, "PLY file '" + file + "': " + msg); };
    std::ifstream in(path, std::ios::binary);
    if (!in) fail("cannot open file");
    const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    size_t pos = 0;
    const PlyHeader header = read_header(data, pos, fail);
    PlyBody body(data, pos, header.format, file, loc);
    MeshData mesh;
    bool have_vertices = false;
    for (const PlyElement &el : header.elements) {
        if (el.props.empty()) continue;
        size_t min_size = 0;
        for (auto &p : el.props) min_size += body.min_bytes(p.is_list ? p.count_type : p.type);
        if (el.count > body.remaining() / std::max<size_t>(min_size, 1))
            body.fail("element '" + el.name + "' declares " + std::to_string(el.count) +
                      " entries, more than the file can hold (truncated or corrupt)");
        if (el.name == "vertex") {
            have_vertices = true;
            read_vertices(body, el, mesh);
        } else if (el.name == "face") {
            read_faces(body, el, mesh);
        } else {
            skip_element(body, el);
        }
    }
    if (!have_vertices) fail("the file has no 'vertex' element");
    if (mesh.indices.empty()) fail("the file contains no faces");
    for (uint32_t i : mesh.indices)
        if (i >= mesh.positions.size())
            fail("a face refers to vertex " + std::to_string(i) + " but there are only " +
                 std::to_string(mesh.positions.size()));
    return mesh;
}

} // namespace mvpt
