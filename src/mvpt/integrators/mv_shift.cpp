#include "mv_shift.h"

namespace mvpt {

ShiftTest shift_to_view(const MvView &l, const MvView &k, int slot, const MvVertex &y, bool scene_moves,
                        ShiftCandidate *out) {
    float t_k;
    if (!shift_time(l, k, y.time, scene_moves, &t_k)) return ShiftTest::Time;
    // Orientation: in front of k within its clip range, and k's lens point on the same side of
    // the surface as l's (so both see the same face of y).
    ShiftGeometry geo;
    if (!k.camera->shift_geometry(y.p, y.n, t_k, y.lens, &geo)) return ShiftTest::Orientation;
    float side = dot(y.n, geo.lens_point - y.p);
    if (!(side * y.side > 0.f) || !(geo.density > 0.f) || !(geo.visible_length > 0.f)) return ShiftTest::Orientation;
    const FilmDesc &film = k.camera->film;
    if (!film.contains(geo.film)) return ShiftTest::Image;
    int px = std::min(int(geo.film.x), film.crop_x + film.crop_width - 1) - film.crop_x;
    int py = std::min(int(geo.film.y), film.crop_y + film.crop_height - 1) - film.crop_y;
    out->slot = slot;
    out->pixel = uint32_t(py) * uint32_t(film.crop_width) + uint32_t(px);
    out->time = t_k;
    out->geo = geo;
    return ShiftTest::Count;
}

} // namespace mvpt
