// The views that may share one native sample (docs/multiview-path-tracing.md §3–§5), held
// as arrays over views, and the loops over them: the shift of y with its cheap tests, the
// viewing directions, the visibility segments and the balance sums D_k. The loops over
// many views are compiled for several instruction sets (core/simd.h).
#pragma once

#include "mv_shift.h"

#include "../../render/camera_projection.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace mvpt {

/// Views per vector of the widest view loop: the tables and arrays over views are padded to a
/// multiple of it, so that the loops run in whole vectors (no scalar remainder).
inline constexpr size_t ViewLanes = 16;
inline size_t whole_lanes(size_t n) { return (n + ViewLanes - 1) / ViewLanes * ViewLanes; }

/// Outcome bits of the cheap tests of the shift of y to one view (ViewShifts::status); 0: a candidate.
enum ShiftStatus : uint8_t {
    ShiftDepth = 1,   ///< y's depth is outside k's clip range or G_k <= 0 (the native view checks only this)
    ShiftFacing = 2,  ///< k's lens point is on the other side of the surface, or y lies at k's near plane
    ShiftOutside = 4, ///< x_k falls outside k's sample window
    ShiftTimeOff = 8, ///< the time test failed
};

/// The test of §3 that a nonzero status reports (time first, then orientation, then image).
inline ShiftTest first_failed_test(uint32_t status) {
    return status & ShiftTimeOff ? ShiftTest::Time : status & (ShiftDepth | ShiftFacing) ? ShiftTest::Orientation
                                                                                         : ShiftTest::Image;
}

/// A view's window of native samples, [x0, x1) x [y0, y1) in full-film pixels: its crop
/// window grown by the margin of its pixel filter, the pixels outside the image whose samples
/// still reach it (design doc §5, "Pixel filters"; none for the box filter).
struct SampleWindow {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    int margin = 0; ///< pixels beyond the crop window on each side
    SampleWindow() = default;
    explicit SampleWindow(const FilmDesc &film);
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    size_t size() const { return size_t(width()) * size_t(height()); }
    bool contains(Vec2f pos) const {
        return pos.x >= float(x0) && pos.x < float(x1) && pos.y >= float(y0) && pos.y < float(y1);
    }
    /// Index of full-film pixel (x, y) in the window (row-major).
    uint32_t index(int x, int y) const { return uint32_t(y - y0) * uint32_t(width()) + uint32_t(x - x0); }
};

/// Sample windows of many views as arrays (by slot), for the image test.
struct FilmTable {
    std::vector<int32_t> x0, y0, x1, y1; ///< [x0, x1) x [y0, y1), full-film pixels
    FilmTable() = default;
    /// The windows of `windows`, then empty windows (every shift falls outside) up to `padded` entries.
    FilmTable(const std::vector<SampleWindow> &windows, size_t padded);
};

/// Shift geometry of many views as arrays by view.
struct ShiftBatch {
    std::vector<float> film_x, film_y, lens_x, lens_y, lens_z, density, visible_length;
};

/// The shift of y to every view, by slot.
struct ViewShifts {
    ShiftBatch geo;                ///< x_k, u_k, G_k, visible length (meaningful where status = 0)
    std::vector<uint32_t> status;  ///< ShiftStatus bits (32-bit: the vector loop's lanes stay float-wide)
    std::vector<uint32_t> pixel;   ///< sample-window pixel index of x_k (where status = 0)
    void resize(size_t n);
};

/// Status and pixel of one view's shift geometry `g` (the same tests as the vector loop).
uint32_t shift_status(const MvVertex &y, bool depth_ok, const ShiftGeometry &g, const SampleWindow &window,
                      uint32_t *pixel);

/// The shift of y to every static view of `table` with the cheap tests (§3 tests 2–3), in one
/// vector loop; `films` holds the same views' sample windows (both padded with whole_lanes).
void shift_static_views(const ProjectionTable &table, const FilmTable &films, const MvVertex &y, ViewShifts &out);

/// The candidates of one native sample: index 0 is the native view l, then every view that
/// passed the cheap tests, by ascending slot.
struct MvCandidates {
    size_t size = 0;
    std::vector<int32_t> slot;
    std::vector<uint32_t> pixel;   ///< sample-window pixel index of x_k
    std::vector<Vec2f> film;       ///< x_k (full-film pixels)
    std::vector<float> g;          ///< film density G_k at y (§4)
    std::vector<float> n;          ///< n_k of the candidate's pixel this pass
    std::vector<float> lx, ly, lz; ///< lens point u_k
    std::vector<float> vis;        ///< length of the segment y -> u_k in front of k's near plane
    std::vector<Vec3f> wi;         ///< direction to u_k in the shading frame at y
    /// Room for `views` candidates and the padding of the vector loops.
    void reserve(size_t views);
    /// Appends view `slot` (of `shifts`) with native count `n_k`.
    void push(const ViewShifts &shifts, int slot, float n_k) {
        const ShiftBatch &b = shifts.geo;
        size_t i = size++;
        this->slot[i] = slot;
        pixel[i] = shifts.pixel[slot];
        film[i] = Vec2f(b.film_x[slot], b.film_y[slot]);
        g[i] = b.density[slot];
        n[i] = n_k;
        lx[i] = b.lens_x[slot], ly[i] = b.lens_y[slot], lz[i] = b.lens_z[slot];
        vis[i] = b.visible_length[slot];
    }
    Point3f lens_point(size_t i) const { return {lx[i], ly[i], lz[i]}; }
    /// g with entries [size, padded) set to 1: the targets of balance_sums when every candidate
    /// is one (padded: size rounded up to a multiple of 8).
    const float *g_padded(size_t padded) {
        std::fill(g.begin() + long(size), g.begin() + long(padded), 1.f);
        return g.data();
    }
};

/// wi[i] = frame.to_local(normalize(u_i - p)) for every candidate (and the padding after them).
void viewing_directions(MvCandidates &c, Point3f p, const Frame &frame);

/// Visibility segments from origin `o` (y offset off its surface) to the lens points of
/// candidates [1, size), into entries [0, size - 1) of arrays of whole_lanes(size - 1) entries:
/// unit directions and lengths up to each view's near plane, shortened by the shadow epsilon;
/// length -1 where nothing can block (y lies at the near plane), the segment is degenerate, or
/// in the padding.
void visibility_segments(const MvCandidates &c, Point3f o, Point3f y, float *dx, float *dy, float *dz, float *t_max);

/// The selection draws of §6 with the Jacobian similarity alone, for candidates [1, size) in one
/// vector loop: s_sel[i] = s_J(G_0 -> G_i) (1 without `jacobian`) and selected[i] = u_i < s_sel[i],
/// u_i the independent sampler's number of the sample `sample_hash` at the dimension whose key
/// (Sampler::dimension_key) `slot_keys` holds for view cand.slot[i]. (s >= 1 selects whatever u is.)
void select_by_jacobian(const MvCandidates &c, const uint64_t *slot_keys, uint64_t sample_hash, bool jacobian,
                        float *s_sel, uint32_t *selected);

/// Balance sums of §5 without pairwise terms, for every target: with r_j = G_j / G_k,
///   D_k = sum_j n_j r_j min(1, r_j)  (`jacobian`, s_J of §6)   or   sum_j n_j r_j,
/// over the `valid` strategies j (arrays g, n), summed in the order of j (deterministic), as
/// (1/G_k) sum_j min(n_j G_j, n_j G_j^2 / G_k) (n_j >= 0, G_j > 0). `g_targets`: the G_k of
/// the targets, padded to a multiple of 8 with positive values; d gets as many entries.
void balance_sums(const float *g, const float *n, size_t valid, const float *g_targets, size_t padded_targets,
                  bool jacobian, float *d);

} // namespace mvpt
