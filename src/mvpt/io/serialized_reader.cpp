// Mitsuba's `.serialized` meshes: a little-endian header (0x041C, version 3
// or 4) followed by a zlib stream per mesh; an offset table at the end of the
// file locates mesh `shape_index` (format described in Mitsuba 3's
// src/shapes/serialized.cpp documentation).
#include "mesh_data.h"

#include <zlib.h>

#include <bit>
#include <cstring>
#include <fstream>
#include <functional>

namespace mvpt {

namespace {

constexpr uint16_t kFormatId = 0x041C;
constexpr uint32_t kHasNormals = 0x0001, kHasTexcoords = 0x0002, kHasColors = 0x0008,
                   kDoublePrecision = 0x2000;
/// zlib cannot expand data by more than about 1032:1; used to bound counts.
constexpr uint64_t kMaxInflateRatio = 1100;

template <typename T> T load_le(const unsigned char *p) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) {
        unsigned char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
        std::memcpy(&v, b, sizeof(T));
    }
    return v;
}

/// Reads bytes from one zlib stream inside the file buffer, on demand.
class Inflater {
public:
    Inflater(const std::string &data, size_t offset, std::function<void(const std::string &)> fail)
        : m_fail(std::move(fail)) {
        std::memset(&m_z, 0, sizeof(m_z));
        if (inflateInit(&m_z) != Z_OK) m_fail("zlib initialisation failed");
        m_z.next_in = (Bytef *)(data.data() + offset);
        m_z.avail_in = uInt(std::min<size_t>(data.size() - offset, UINT32_MAX));
    }
    ~Inflater() { inflateEnd(&m_z); }
    Inflater(const Inflater &) = delete;
    Inflater &operator=(const Inflater &) = delete;

    void read(void *dst, size_t n, const char *what) {
        auto *out = (unsigned char *)dst;
        while (n > 0) {
            if (m_done) m_fail(std::string("compressed data ends early (while reading ") + what + ")");
            size_t chunk = std::min<size_t>(n, 1u << 30);
            m_z.next_out = out;
            m_z.avail_out = uInt(chunk);
            int rc = inflate(&m_z, Z_NO_FLUSH);
            size_t got = chunk - m_z.avail_out;
            out += got;
            n -= got;
            if (rc == Z_STREAM_END) m_done = true;
            else if (rc != Z_OK) m_fail(std::string("corrupt compressed data (zlib: ") + (m_z.msg ? m_z.msg : "error") + ")");
            else if (got == 0 && m_z.avail_in == 0) m_fail(std::string("file is truncated (while reading ") + what + ")");
        }
    }
    template <typename T> T get(const char *what) {
        unsigned char b[sizeof(T)];
        read(b, sizeof(T), what);
        return load_le<T>(b);
    }

private:
    z_stream m_z;
    bool m_done = false;
    std::function<void(const std::string &)> m_fail;
};

using Fail = std::function<void(const std::string &)>;

/// Where mesh `shape_index` starts, from the dictionary at the end of the file.
size_t mesh_offset(const std::string &data, uint16_t version, int shape_index, const Fail &fail) {
    if (shape_index == 0) return 0;
    auto bytes = [&](size_t off) { return (const unsigned char *)data.data() + off; };
    if (data.size() < 8) fail("file is truncated (no offset dictionary)");
    const uint32_t count = load_le<uint32_t>(bytes(data.size() - 4));
    if (uint32_t(shape_index) >= count)
        fail("shape_index " + std::to_string(shape_index) + " is out of range (the file holds " + std::to_string(count) +
             " meshes)");
    const size_t entry = version == 4 ? 8 : 4;
    if (uint64_t(count) * entry + 4 > data.size()) fail("corrupt offset dictionary");
    const size_t at = data.size() - 4 - entry * size_t(count - uint32_t(shape_index));
    const uint64_t off = version == 4 ? load_le<uint64_t>(bytes(at)) : load_le<uint32_t>(bytes(at));
    if (off > data.size() - 4) fail("offset of mesh " + std::to_string(shape_index) + " lies outside the file");
    if (load_le<uint16_t>(bytes(size_t(off))) != kFormatId)
        fail("mesh " + std::to_string(shape_index) + " does not start with a valid header");
    return size_t(off);
}

/// The vertex and face counts after the flags (and, in version 4, the shape's name), checked
/// against what `file_size` bytes can inflate to.
void read_counts(Inflater &z, uint16_t version, size_t fsize, size_t file_size, uint64_t &vertices, uint64_t &faces,
                 const Fail &fail) {
    if (version == 4) {
        // Null-terminated shape name (bounded: a name is short).
        for (int i = 0;; ++i) {
            if (i > 1 << 16) fail("unterminated shape name");
            char c;
            z.read(&c, 1, "shape name");
            if (c == 0) break;
        }
    }
    vertices = z.get<uint64_t>("vertex count"), faces = z.get<uint64_t>("face count");
    const uint64_t budget = uint64_t(file_size) * kMaxInflateRatio;
    if (vertices == 0 || faces == 0) fail("the mesh is empty");
    if (vertices > budget / (3 * fsize) || faces > budget / 12)
        fail("vertex/face counts (" + std::to_string(vertices) + ", " + std::to_string(faces) +
             ") are larger than the file can hold (corrupt)");
    if (vertices > UINT32_MAX) fail("meshes with more than 2^32 vertices are not supported");
}

/// `count` x `dim` floats (stored as doubles when `dp`).
std::vector<float> read_floats(Inflater &z, bool dp, uint64_t count, size_t dim, const char *what) {
    std::vector<float> out(size_t(count) * dim);
    if (dp) {
        std::vector<double> tmp(out.size());
        z.read(tmp.data(), tmp.size() * 8, what);
        for (size_t i = 0; i < out.size(); ++i) out[i] = float(load_le<double>((const unsigned char *)&tmp[i]));
    } else {
        z.read(out.data(), out.size() * 4, what);
        if constexpr (std::endian::native == std::endian::big)
            for (auto &f : out) f = load_le<float>((const unsigned char *)&f);
    }
    return out;
}

/// The mesh's vertex attributes and faces, after its counts.
MeshData read_mesh(Inflater &z, uint32_t flags, uint64_t vertices, uint64_t faces, const Fail &fail) {
    const bool dp = (flags & kDoublePrecision) != 0;
    MeshData mesh;
    const std::vector<float> p = read_floats(z, dp, vertices, 3, "vertex positions");
    mesh.positions.resize(size_t(vertices));
    for (size_t i = 0; i < mesh.positions.size(); ++i) mesh.positions[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
    if (flags & kHasNormals) {
        const std::vector<float> n = read_floats(z, dp, vertices, 3, "vertex normals");
        mesh.normals.resize(size_t(vertices));
        for (size_t i = 0; i < mesh.normals.size(); ++i) mesh.normals[i] = {n[3 * i], n[3 * i + 1], n[3 * i + 2]};
    }
    if (flags & kHasTexcoords) {
        const std::vector<float> t = read_floats(z, dp, vertices, 2, "texture coordinates");
        mesh.uvs.resize(size_t(vertices));
        for (size_t i = 0; i < mesh.uvs.size(); ++i) mesh.uvs[i] = {t[2 * i], t[2 * i + 1]};
    }
    if (flags & kHasColors) read_floats(z, dp, vertices, 3, "vertex colours"); // read and ignored (as Mitsuba does)
    mesh.indices.resize(size_t(faces) * 3);
    z.read(mesh.indices.data(), mesh.indices.size() * 4, "face indices");
    if constexpr (std::endian::native == std::endian::big)
        for (auto &i : mesh.indices) i = load_le<uint32_t>((const unsigned char *)&i);
    for (uint32_t i : mesh.indices)
        if (i >= vertices)
            fail("a face refers to vertex " + std::to_string(i) + " but there are only " + std::to_string(vertices));
    return mesh;
}

} // namespace

MeshData read_serialized(const std::filesystem::path &path, int shape_index, const FileLoc &loc) {
    const std::string file = path.string();
    const Fail fail = [&](const std::string &msg) { throw SceneError(loc, "serialized file '" + file + "': " + msg); };
    std::ifstream in(path, std::ios::binary);
    if (!in) fail("cannot open file");
    const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (data.size() < 4) fail("file is truncated (no header)");
    auto header = [&](size_t off) { return load_le<uint16_t>((const unsigned char *)data.data() + off); };
    if (header(0) != kFormatId) fail("not a Mitsuba serialized mesh (bad format identifier)");
    const uint16_t version = header(2);
    if (version != 3 && version != 4) fail("unsupported version " + std::to_string(version) + " (expected 3 or 4)");
    if (shape_index < 0) fail("shape_index must be non-negative");
    Inflater z(data, mesh_offset(data, version, shape_index, fail) + 4, fail);
    const uint32_t flags = z.get<uint32_t>("flags");
    uint64_t vertices = 0, faces = 0;
    read_counts(z, version, (flags & kDoublePrecision) ? 8 : 4, data.size(), vertices, faces, fail);
    return read_mesh(z, flags, vertices, faces, fail);
}

} // namespace mvpt
