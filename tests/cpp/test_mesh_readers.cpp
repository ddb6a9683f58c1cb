// PLY and serialized readers: formats, property handling, and clean failures
// on truncated or corrupt files.
#include "mvpt/io/mesh_data.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <bit>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

using namespace mvpt;
namespace fs = std::filesystem;

namespace {

fs::path temp_file(const std::string &name, const std::string &content) {
    fs::path dir = fs::temp_directory_path() / "mvpt_reader_tests";
    fs::create_directories(dir);
    fs::path p = dir / name;
    std::ofstream(p, std::ios::binary) << content;
    return p;
}

template <typename T> void put(std::string &s, T v, bool big_endian = false) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
    s.append(b, sizeof(T));
}

/// Expect a SceneError whose message names the file and contains `what`.
void expect_error(const fs::path &p, const std::string &what, bool ply = true) {
    try {
        if (ply) read_ply(p, {"scene.xml", 3, 5});
        else read_serialized(p, 0, {"scene.xml", 3, 5});
        FAIL() << "no error for " << p;
    } catch (const SceneError &e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
        EXPECT_NE(msg.find(what), std::string::npos) << msg;
        EXPECT_NE(msg.find("scene.xml:3:5"), std::string::npos) << msg;
    }
}

const char *kAsciiPly = R"(ply
format ascii 1.0
comment made by hand
element vertex 4
property float x
property float y
property float z
property float confidence
property float nx
property float ny
property float nz
property float s
property float t
element face 1
property uchar flags
property list uchar int vertex_indices
element edge 1
property list uchar int vertex1
end_header
0 0 0 9 0 0 1 0 0
1 0 0 9 0 0 1 1 0
1 1 0 9 0 0 1 1 1
0 1 0 9 0 0 1 0 1
7 4 0 1 2 3
2 0 1
)";

std::string binary_ply(bool big) {
    std::string s = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
                    "property list uchar short junk\nproperty float texture_u\nproperty float texture_v\n"
                    "element face 2\nproperty list int uint vertex_index\nproperty ushort extra\nend_header\n";
    double pos[3][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}};
    for (int v = 0; v < 3; ++v) {
        for (double c : pos[v]) put(s, c, big);
        put<uint8_t>(s, 2, big);
        put<int16_t>(s, -5, big);
        put<int16_t>(s, 7, big);
        put<float>(s, 0.25f * float(v), big);
        put<float>(s, 0.5f, big);
    }
    put<int32_t>(s, 3, big);
    for (uint32_t i : {0u, 1u, 2u}) put(s, i, big);
    put<uint16_t>(s, 1, big);
    put<int32_t>(s, 3, big);
    for (uint32_t i : {2u, 1u, 0u}) put(s, i, big);
    put<uint16_t>(s, 1, big);
    return s;
}

} // namespace

TEST(PlyReader, AsciiWithAliasesSkippedPropertiesAndQuads) {
    MeshData m = read_ply(temp_file("ascii.ply", kAsciiPly), {});
    ASSERT_EQ(m.positions.size(), 4u);
    ASSERT_EQ(m.normals.size(), 4u);
    ASSERT_EQ(m.uvs.size(), 4u);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3})); // fan triangulation
    EXPECT_FLOAT_EQ(m.positions[2].y, 1.f);
    EXPECT_FLOAT_EQ(m.normals[1].z, 1.f);
    EXPECT_FLOAT_EQ(m.uvs[2].x, 1.f);
    EXPECT_FLOAT_EQ(m.uvs[3].y, 1.f);
    EXPECT_TRUE(m.attributes.empty()); // 'confidence' and 'flags' have no channel suffix
}

/// The attribute `name` of `m` (a test failure and an empty one when it is missing).
const MeshAttribute &attribute(const MeshData &m, const std::string &name) {
    static const MeshAttribute none;
    for (const MeshAttribute &a : m.attributes)
        if (a.name == name) return a;
    ADD_FAILURE() << "no attribute " << name;
    return none;
}

TEST(PlyReader, MeshAttributesByMitsubasNamingScheme) {
    // Vertex: an 8-bit colour with alpha, a 1-channel weight, a 2-channel run (not an
    // attribute), a 1..3 run; faces (a quad and a triangle): a float colour, a scalar, an _r _g _b run.
    const char *ply = R"(ply
format ascii 1.0
element vertex 5
property float x
property float y
property float z
property uchar red
property uchar green
property uchar blue
property uchar alpha
property float weight_0
property float dir_x
property float dir_y
property float n_1
property float n_2
property float n_3
element face 2
property list uchar int vertex_indices
property float r
property float g
property float b
property float w_0
property float tint_r
property float tint_g
property float tint_b
end_header
0 0 0 255 0 51 255 0.5 1 2 1 2 3
1 0 0 0 255 0 255 1.5 1 2 4 5 6
1 1 0 0 0 255 255 2.5 1 2 7 8 9
0 1 0 255 255 255 255 3.5 1 2 1 1 1
2 2 0 0 0 0 0 4.5 1 2 0 0 0
4 0 1 2 3 0.1 0.2 0.3 7 0.4 0.5 0.6
3 1 4 2 0.7 0.8 0.9 8 1.0 1.1 1.2
)";
    const MeshData m = read_ply(temp_file("attributes.ply", ply), {});
    ASSERT_EQ(m.triangle_count(), 3u);
    std::vector<std::string> names;
    for (const MeshAttribute &a : m.attributes) names.push_back(a.name);
    EXPECT_EQ(names, (std::vector<std::string>{"vertex_color", "vertex_weight", "vertex_n", "face_color", "face_w",
                                               "face_tint_color"}));
    const MeshAttribute &vc = attribute(m, "vertex_color");
    EXPECT_EQ(vc.dim, 3);
    ASSERT_EQ(vc.values.size(), 15u); // alpha not read
    EXPECT_FLOAT_EQ(vc.values[0], 1.f);
    EXPECT_FLOAT_EQ(vc.values[2], 0.2f); // 51 / 255
    EXPECT_FLOAT_EQ(vc.values[4], 1.f);
    const MeshAttribute &w = attribute(m, "vertex_weight");
    EXPECT_EQ(w.dim, 1);
    EXPECT_EQ(w.values, (std::vector<float>{0.5f, 1.5f, 2.5f, 3.5f, 4.5f}));
    const MeshAttribute &n = attribute(m, "vertex_n");
    EXPECT_EQ(n.dim, 3);
    EXPECT_FLOAT_EQ(n.values[3 * 2 + 1], 8.f);
    // Face attributes: one entry per triangle, the quad's twice.
    const MeshAttribute &fc = attribute(m, "face_color");
    EXPECT_FALSE(vc.per_face());
    EXPECT_TRUE(fc.per_face());
    EXPECT_EQ(fc.values, (std::vector<float>{0.1f, 0.2f, 0.3f, 0.1f, 0.2f, 0.3f, 0.7f, 0.8f, 0.9f}));
    EXPECT_EQ(attribute(m, "face_w").values, (std::vector<float>{7.f, 7.f, 8.f}));
    EXPECT_EQ(attribute(m, "face_tint_color").values,
              (std::vector<float>{0.4f, 0.5f, 0.6f, 0.4f, 0.5f, 0.6f, 1.0f, 1.1f, 1.2f}));
}

TEST(PlyReader, BinaryBothEndiannesses) {
    for (bool big : {false, true}) {
        MeshData m = read_ply(temp_file(big ? "be.ply" : "le.ply", binary_ply(big)), {});
        ASSERT_EQ(m.positions.size(), 3u) << big;
        EXPECT_TRUE(m.normals.empty());
        ASSERT_EQ(m.uvs.size(), 3u);
        EXPECT_FLOAT_EQ(m.positions[1].x, 2.f);
        EXPECT_FLOAT_EQ(m.positions[2].y, 3.f);
        EXPECT_FLOAT_EQ(m.uvs[2].x, 0.5f);
        EXPECT_FLOAT_EQ(m.uvs[1].y, 0.5f);
        EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 2, 1, 0}));
        EXPECT_TRUE(m.attributes.empty());
    }
}

TEST(PlyReader, TruncatedAndCorruptFilesFailCleanly) {
    std::string bin = binary_ply(false);
    for (size_t cut : {bin.size() - 1, bin.size() - 20, bin.size() - 60})
        expect_error(temp_file("cut.ply", bin.substr(0, cut)), "truncated");
    std::string huge = bin;
    huge.replace(huge.find("element vertex 3"), 16, "element vertex 900000000000");
    expect_error(temp_file("huge.ply", huge), "more than the file can hold");
    std::string bad_index = kAsciiPly;
    bad_index.replace(bad_index.find("4 0 1 2 3"), 9, "4 0 1 2 9");
    expect_error(temp_file("index.ply", bad_index), "refers to vertex 9");
    std::string garbage = kAsciiPly;
    garbage.replace(garbage.find("1 1 0 9"), 7, "1 x 0 9");
    expect_error(temp_file("garbage.ply", garbage), "expected a number");
    expect_error(temp_file("noheader.ply", "ply\nformat ascii 1.0\nelement vertex 1\n"), "end_header");
    expect_error(temp_file("magic.ply", "PLY?\n"), "not a PLY file");
    std::string list = bin;
    // A face whose vertex list claims 2^31 entries.
    size_t face0 = list.size() - 2 * (4 + 12 + 2);
    list[face0 + 3] = 0x7f;
    expect_error(temp_file("list.ply", list), "more than the file can hold");
}

// ---------------------------------------------------------------- serialized

namespace {

std::string serialized_mesh(uint16_t version, bool dp, bool normals, bool uvs, float offset) {
    std::string raw;
    uint32_t flags = (normals ? 1u : 0u) | (uvs ? 2u : 0u) | (dp ? 0x2000u : 0x1000u);
    put(raw, flags);
    if (version == 4) raw += std::string("tri") + '\0';
    put<uint64_t>(raw, 3);
    put<uint64_t>(raw, 1);
    auto value = [&](double v) { dp ? put<double>(raw, v) : put<float>(raw, float(v)); };
    for (double v : {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0}) value(v + offset);
    if (normals)
        for (int i = 0; i < 3; ++i) { value(0); value(0); value(1); }
    if (uvs)
        for (double v : {0.0, 0.0, 1.0, 0.0, 0.0, 1.0}) value(v);
    for (uint32_t i : {0u, 1u, 2u}) put(raw, i);
    uLongf len = compressBound(uLong(raw.size()));
    std::string z(len, '\0');
    compress((Bytef *)z.data(), &len, (const Bytef *)raw.data(), uLong(raw.size()));
    z.resize(len);
    std::string out;
    put<uint16_t>(out, 0x041C);
    put<uint16_t>(out, version);
    return out + z;
}

std::string serialized_file(uint16_t version, bool dp) {
    std::string a = serialized_mesh(version, dp, true, true, 0.f), b = serialized_mesh(version, dp, false, false, 5.f);
    std::string f = a + b;
    if (version == 4) { put<uint64_t>(f, 0); put<uint64_t>(f, a.size()); }
    else { put<uint32_t>(f, 0); put<uint32_t>(f, uint32_t(a.size())); }
    put<uint32_t>(f, 2);
    return f;
}

} // namespace

TEST(SerializedReader, VersionsPrecisionsAndShapeIndex) {
    for (uint16_t version : {3, 4})
        for (bool dp : {false, true}) {
            auto p = temp_file("mesh.serialized", serialized_file(version, dp));
            MeshData m0 = read_serialized(p, 0, {});
            ASSERT_EQ(m0.positions.size(), 3u);
            EXPECT_EQ(m0.normals.size(), 3u);
            EXPECT_EQ(m0.uvs.size(), 3u);
            EXPECT_FLOAT_EQ(m0.positions[1].x, 1.f);
            EXPECT_FLOAT_EQ(m0.uvs[2].y, 1.f);
            MeshData m1 = read_serialized(p, 1, {});
            EXPECT_TRUE(m1.normals.empty() && m1.uvs.empty());
            EXPECT_FLOAT_EQ(m1.positions[0].x, 5.f);
            EXPECT_EQ(m1.indices, (std::vector<uint32_t>{0, 1, 2}));
            EXPECT_THROW(read_serialized(p, 2, {}), SceneError);
        }
}

TEST(SerializedReader, CorruptFilesFailCleanly) {
    std::string f = serialized_file(4, false);
    size_t first = serialized_mesh(4, false, true, true, 0.f).size();
    for (size_t cut : {size_t(3), size_t(10), first / 2, first - 8})
        expect_error(temp_file("cut.serialized", f.substr(0, cut)), "", false);
    std::string bad = f;
    bad[0] = 0x1d;
    expect_error(temp_file("bad.serialized", bad), "format identifier", false);
    std::string junk = f;
    for (size_t i = 8; i < 30; ++i) junk[i] = char(0x55);
    expect_error(temp_file("junk.serialized", junk), "", false);
}

TEST(SerializedReader, DictionaryOffsetsOutsideTheFileFailCleanly) {
    // Offsets near 2^64 once wrapped around the bounds check (an out-of-bounds read).
    for (uint64_t off : {~uint64_t(0), ~uint64_t(0) - 3, uint64_t(1) << 40}) {
        std::string f = serialized_file(4, false);
        std::memcpy(&f[f.size() - 4 - 8], &off, 8);
        auto p = temp_file("offset.serialized", f);
        try {
            read_serialized(p, 1, {"scene.xml", 3, 5});
            FAIL() << "no error for offset " << off;
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find("lies outside the file"), std::string::npos) << e.what();
        }
    }
}

TEST(SerializedReader, MatpreviewFile) {
    const char *env = std::getenv("MVPT_SHARED");
    fs::path root = env ? fs::path(env) / "scenes" : fs::path("/work/shared/scenes");
    fs::path p = root / "m3data-matpreview" / "matpreview.serialized";
    if (!fs::exists(p)) GTEST_SKIP() << "shared scenes not available";
    size_t total = 0;
    for (int i = 0;; ++i) {
        MeshData m;
        try {
            m = read_serialized(p, i, {});
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
            EXPECT_GE(i, 1);
            break;
        }
        EXPECT_GT(m.triangle_count(), 0u);
        for (uint32_t idx : m.indices) ASSERT_LT(idx, m.positions.size());
        total += m.triangle_count();
    }
    EXPECT_GT(total, 60000u); // the README quotes 61.6k triangles
}
