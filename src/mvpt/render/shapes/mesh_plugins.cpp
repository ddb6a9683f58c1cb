// Shape plugins that produce triangle meshes: obj, rectangle, cube.
#include "mesh.h"

namespace mvpt {

namespace {

std::shared_ptr<Object> make_obj(const Properties &props, const LoadContext &ctx) {
    std::string file = props.get_string("filename");
    auto path = ctx.resolve(file, props.loc_of("filename"));
    MeshData data = read_obj(path, props.loc_of("filename"));
    return std::make_shared<TriangleMesh>(std::move(data), props, "OBJ mesh '" + file + "'");
}

/// Mitsuba's rectangle: [-1, 1]^2 in the z = 0 plane, normal +z.
MeshData rectangle_data() {
    MeshData m;
    m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

/// Mitsuba's cube: [-1, 1]^3 with outward normals, four vertices per face.
MeshData cube_data() {
    MeshData m;
    const Vec3f normals[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const Vec3f &n : normals) {
        Frame f(n);
        uint32_t base = uint32_t(m.positions.size());
        const Vec2f corners[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (const Vec2f &c : corners) {
            m.positions.push_back(n + f.s * c.x + f.t * c.y);
            m.normals.push_back(n);
            m.uvs.push_back({(c.x + 1) * 0.5f, (c.y + 1) * 0.5f});
        }
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
    return m;
}

std::shared_ptr<Object> make_rectangle(const Properties &props, const LoadContext &) {
    return std::make_shared<TriangleMesh>(rectangle_data(), props, "rectangle");
}

std::shared_ptr<Object> make_cube(const Properties &props, const LoadContext &) {
    return std::make_shared<TriangleMesh>(cube_data(), props, "cube");
}

} // namespace

MVPT_REGISTER_PLUGIN("shape", "obj", make_obj);
MVPT_REGISTER_PLUGIN("shape", "rectangle", make_rectangle);
MVPT_REGISTER_PLUGIN("shape", "cube", make_cube);

} // namespace mvpt
