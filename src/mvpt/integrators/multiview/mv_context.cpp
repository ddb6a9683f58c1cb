#include "mv_context.h"

#include "mv_media.h"

#include "../../accel/scene.h"
#include "../../render/camera.h"
#include "../../render/light.h"

#include <cmath>

namespace mvpt {

MvViewStats &MvViewStats::operator+=(const MvViewStats &o) {
    native += o.native; received += o.received; tried += o.tried; sharing += o.sharing; rays += o.rays;
    for (int i = 0; i < int(ShiftTest::Count); ++i) rejected[i] += o.rejected[i];
    return *this;
}

bool mv_scene_moves(const Scene &scene) {
    bool moves = scene.is_animated();
    for (const auto &light : scene.lights()) moves |= light->moves();
    return moves;
}

void MvContext::prepare() {
    all_time_compatible = all_time_compatible_equal_dt = true;
    for (const MvView &a : views)
        for (const MvView &b : views) {
            all_time_compatible &= time_compatible(a, b, scene_moves);
            all_time_compatible_equal_dt &= a.dt == b.dt;
        }
    select_keys.clear();
    for (const MvView &v : views) select_keys.push_back(Sampler::dimension_key(DimSelectBase + v.scene_index));
    std::vector<CameraProjection> proj;
    static_shift = !scene_moves && all_time_compatible;
    for (const MvView &v : views) {
        const CameraProjection *p = v.camera->static_projection();
        static_shift &= p != nullptr;
        proj.push_back(p ? *p : CameraProjection{});
    }
    // Padded to whole vectors with copies of a real camera whose film window is empty.
    const size_t padded = whole_lanes(views.size());
    if (!proj.empty()) proj.resize(padded, proj.back());
    projections = ProjectionTable(proj);
    windows.clear();
    for (const MvView &v : views) windows.emplace_back(v.camera->film);
    films = FilmTable(windows, padded);
    if (views.size() >= 2) {
        auto centre = [](const MvView &v) {
            const FilmDesc &f = v.camera->film;
            Vec2f mid(float(f.crop_x) + 0.5f * float(f.crop_width), float(f.crop_y) + 0.5f * float(f.crop_height));
            return v.camera->generate_ray(mid, Vec2f(0.f, 0.f), v.t0).o;
        };
        Vec3f d = centre(views[1]) - centre(views[0]);
        if (squared_norm(d) > 0.f && std::isfinite(squared_norm(d))) across = normalize(d);
    }
    medium_vertices = mv_can_share_medium_vertices(*this);
}

} // namespace mvpt
