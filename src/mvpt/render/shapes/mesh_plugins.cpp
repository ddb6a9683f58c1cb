// Shape plugins that produce triangle meshes: obj, ply, serialized, rectangle, cube.
#include "instance.h"
#include "mesh.h"

namespace mvpt {

namespace {

/// A mesh shape from `data`, static or (with an animated to_world) motion-blurred; what it
/// lost to bad data is a warning in `ctx` (its zero-area triangles a note), naming the shape's
/// place in the scene file.
std::shared_ptr<Object> make_mesh(MeshData data, const Properties &props, const std::string &what,
                                  const LoadContext &ctx) {
    return make_maybe_animated(props, [&](const Transform &to_world) {
        auto mesh = std::make_shared<TriangleMesh>(std::move(data), props, to_world, what);
        if (std::string w = mesh->data_warning(what); !w.empty()) ctx.warn(props.loc().str() + ": " + w);
        if (std::string n = mesh->data_note(what); !n.empty()) ctx.note(props.loc().str() + ": " + n);
        return mesh;
    });
}

std::shared_ptr<Object> make_obj(const Properties &props, const LoadContext &ctx) {
    std::string file = props.get_string("filename");
    auto path = ctx.resolve(file, props.loc_of("filename"));
    MeshData data = read_obj(path, props.loc_of("filename"));
    // Mitsuba flips v by default, for consistency with Mitsuba 0.6.
    if (props.get_bool("flip_tex_coords", true))
        for (Vec2f &uv : data.uvs) uv.y = 1.f - uv.y;
    return make_mesh(std::move(data), props, "OBJ mesh '" + file + "'", ctx);
}

std::shared_ptr<Object> make_ply(const Properties &props, const LoadContext &ctx) {
    std::string file = props.get_string("filename");
    auto path = ctx.resolve(file, props.loc_of("filename"));
    MeshData data = read_ply(path, props.loc_of("filename"));
    return make_mesh(std::move(data), props, "PLY mesh '" + file + "'", ctx);
}

std::shared_ptr<Object> make_serialized(const Properties &props, const LoadContext &ctx) {
    std::string file = props.get_string("filename");
    auto path = ctx.resolve(file, props.loc_of("filename"));
    int64_t index = props.get_int("shape_index", 0);
    if (index < 0 || index > INT32_MAX) props.fail("shape_index", "shape_index must be a non-negative integer");
    MeshData data = read_serialized(path, int(index), props.loc_of("filename"));
    return make_mesh(std::move(data), props, "serialized mesh '" + file + "'@" + std::to_string(index), ctx);
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
    return make_maybe_animated(props, [&](const Transform &to_world) {
        MeshData data = rectangle_data();
        // Mitsuba's rectangle is analytic: its normal is +z transformed as a normal, also under a
        // mirroring to_world, where the triangles' winding would give the opposite side.
        if (to_world.flips_handedness())
            for (size_t t = 0; t < data.indices.size(); t += 3) std::swap(data.indices[t + 1], data.indices[t + 2]);
        return std::make_shared<TriangleMesh>(std::move(data), props, to_world, "rectangle");
    });
}

std::shared_ptr<Object> make_cube(const Properties &props, const LoadContext &) {
    // A cube flattened by its to_world (a common two-sided panel) loses its sides by design: no warning.
    return make_mesh(cube_data(), props, "cube", LoadContext{});
}

} // namespace

MVPT_REGISTER_PLUGIN("shape", "obj", make_obj);
MVPT_REGISTER_PLUGIN("shape", "ply", make_ply);
MVPT_REGISTER_PLUGIN("shape", "serialized", make_serialized);
MVPT_REGISTER_PLUGIN("shape", "rectangle", make_rectangle);
MVPT_REGISTER_PLUGIN("shape", "cube", make_cube);

} // namespace mvpt
