#include "mv_candidates.h"

#include <algorithm>
#include <cmath>

#include "../../core/simd.h"
#include "../../core/sampler.h"
#include "../../render/interaction.h"

namespace mvpt {

SampleWindow::SampleWindow(const FilmDesc &film) {
    // Pixel centres lie half a pixel inside their pixel: the filters of the crop window's
    // pixels reach radius - 1/2 beyond it.
    margin = film.filter && !film.filter->is_box() ? int(std::ceil(film.filter->radius() - 0.5f)) : 0;
    x0 = film.crop_x - margin, y0 = film.crop_y - margin;
    x1 = film.crop_x + film.crop_width + margin, y1 = film.crop_y + film.crop_height + margin;
}

FilmTable::FilmTable(const std::vector<SampleWindow> &windows, size_t padded)
    : x0(padded, 0), y0(padded, 0), x1(padded, 0), y1(padded, 0) {
    for (size_t k = 0; k < windows.size(); ++k) {
        x0[k] = windows[k].x0;
        y0[k] = windows[k].y0;
        x1[k] = windows[k].x1;
        y1[k] = windows[k].y1;
    }
}

void ViewShifts::resize(size_t n) {
    if (status.size() == n) return; // the number of views is fixed for a render
    for (auto *v : {&geo.film_x, &geo.film_y, &geo.lens_x, &geo.lens_y, &geo.lens_z, &geo.density, &geo.visible_length})
        v->resize(n);
    status.resize(n);
    pixel.resize(n);
}

namespace {

/// The cheap tests of §3 on one view's shift geometry, branch-free: orientation (y in the
/// clip range, G > 0, k's lens point on the native lens point's side of the surface, or any
/// side for a point in a medium, y beyond k's near plane) and image bounds; the pixel index
/// is computed from the clamped position.
[[gnu::always_inline]] inline uint32_t status_of(const MvVertex &y, bool depth_ok, const ShiftGeometry &g, int32_t x0,
                                                int32_t y0, int32_t x1, int32_t y1, uint32_t *pixel) {
    float side = dot(y.n, g.lens_point - y.p);
    bool depth = depth_ok & (g.density > 0.f);
    bool facing = ((side * y.side > 0.f) | y.in_medium) & (g.visible_length > 0.f);
    float fx0 = float(x0), fy0 = float(y0), fx1 = float(x1), fy1 = float(y1);
    bool inside = (g.film.x >= fx0) & (g.film.x < fx1) & (g.film.y >= fy0) & (g.film.y < fy1);
    // Clamped into the window first (a NaN becomes x0), so the conversion is always defined.
    float cx = g.film.x > fx0 ? g.film.x : fx0, cy = g.film.y > fy0 ? g.film.y : fy0;
    cx = cx < fx1 - 1.f ? cx : fx1 - 1.f;
    cy = cy < fy1 - 1.f ? cy : fy1 - 1.f;
    // (Offsets from the window's corner are >= 0, so truncation is floor; the corner may be negative.
    // Converted through int32, which AVX2 converts as vectors, unlike float to uint32.)
    *pixel = uint32_t(int32_t(cy - fy0)) * uint32_t(x1 - x0) + uint32_t(int32_t(cx - fx0));
    return (depth ? 0u : uint32_t(ShiftDepth)) | (facing ? 0u : uint32_t(ShiftFacing)) |
           (inside ? 0u : uint32_t(ShiftOutside));
}

MVPT_MULTI_ISA void shift_kernel(const float *__restrict proj, const int32_t *__restrict wx0,
                                 const int32_t *__restrict wy0, const int32_t *__restrict wx1,
                                 const int32_t *__restrict wy1, size_t n, MvVertex y, float *__restrict fx,
                                 float *__restrict fy, float *__restrict lx, float *__restrict ly, float *__restrict lz,
                                 float *__restrict dens, float *__restrict vis, uint32_t *__restrict status,
                                 uint32_t *__restrict pixel) {
    const ShiftVertex v(y.p, y.n);
    for (size_t k = 0; k < n; ++k) {
        ShiftGeometry g;
        bool ok = shift_geometry(ProjectionTable::at(proj, n, k), v, y.lens, &g);
        fx[k] = g.film.x;
        fy[k] = g.film.y;
        lx[k] = g.lens_point.x;
        ly[k] = g.lens_point.y;
        lz[k] = g.lens_point.z;
        dens[k] = g.density;
        vis[k] = g.visible_length;
        status[k] = status_of(y, ok, g, wx0[k], wy0[k], wx1[k], wy1[k], &pixel[k]);
    }
}

MVPT_MULTI_ISA void direction_kernel(const float *__restrict lx, const float *__restrict ly, const float *__restrict lz,
                                     size_t n, Point3f p, Frame f, Vec3f *__restrict wi) {
    for (size_t i = 0; i < n; ++i) {
        Vec3f w(lx[i] - p.x, ly[i] - p.y, lz[i] - p.z);
        w = w * (1.f / norm(w));
        wi[i] = f.to_local(w);
    }
}

MVPT_MULTI_ISA void segment_kernel(const float *__restrict lx, const float *__restrict ly, const float *__restrict lz,
                                   const float *__restrict vis, size_t n, Point3f o, Point3f y, float *__restrict dx,
                                   float *__restrict dy, float *__restrict dz, float *__restrict t_max) {
    for (size_t i = 0; i < n; ++i) {
        Vec3f d(lx[i] - o.x, ly[i] - o.y, lz[i] - o.z), w(lx[i] - y.x, ly[i] - y.y, lz[i] - y.z);
        float dist = norm(d);
        // The visible length is measured from y; from the offset origin it is shorter or longer
        // by the difference of the two distances to the lens point.
        float len = vis[i] - (norm(w) - dist);
        float inv = 1.f / dist;
        dx[i] = d.x * inv;
        dy[i] = d.y * inv;
        dz[i] = d.z * inv;
        bool traced = (len > 0.f) & (dist > 0.f) & (dist < Infinity); // a finite segment with room to block
        t_max[i] = select(traced, len * (1.f - ShadowEpsilon), -1.f); // bit select: the loop has no branch
    }
}

/// D of `Blocks` vectors of eight targets from t0 on: with a_j = n_j G_j and b_j = a_j G_j,
///   n_j r min(1, r) = min(a_j, b_j / G_k) / G_k   (r = G_j / G_k, n_j >= 0),
/// so each j costs a multiply, a min and an add per vector, and 1/G_k leaves the sum. The j loop
/// is outermost, so its two broadcasts serve every vector; each lane sums over j in order.
/// (Always inlined: a call would pass the vectors through memory in the default ISA.)
template <int Blocks, typename F8>
[[gnu::always_inline]] inline void balance_blocks(const float *__restrict g, const float *__restrict nn, size_t nv,
                                                  const float *__restrict g_targets, size_t t0, bool jacobian,
                                                  float *__restrict d) {
    F8 inv_gk[Blocks], acc[Blocks];
    for (int b = 0; b < Blocks; ++b) {
        inv_gk[b] = 1.f / simd::load<F8>(g_targets + t0 + 8 * b);
        acc[b] = F8{};
    }
    if (jacobian)
        for (size_t j = 0; j < nv; ++j) {
            const float a = nn[j] * g[j], bj = a * g[j];
            const F8 av = {a, a, a, a, a, a, a, a};
            for (int b = 0; b < Blocks; ++b) {
                F8 t = bj * inv_gk[b];
                acc[b] += t < av ? t : av; // one vminps
            }
        }
    else
        for (size_t j = 0; j < nv; ++j) {
            const float a = nn[j] * g[j];
            for (int b = 0; b < Blocks; ++b) acc[b] += a;
        }
    for (int b = 0; b < Blocks; ++b) {
        simd::store(d + t0 + 8 * b, F8(acc[b] * inv_gk[b]));
    }
}

MVPT_MULTI_ISA void balance_kernel(const float *__restrict g, const float *__restrict nn, size_t nv,
                                   const float *__restrict g_targets, size_t padded_targets, bool jacobian,
                                   float *__restrict d) {
    // Targets in the lanes of 8-wide vectors, up to four vectors per pass over j. (One 64-byte
    // vector type would halve the loop on AVX-512 but GCC lowers it through memory in the AVX2
    // clone: 5x the instructions.)
    using F8 = simd::f32x8;
    size_t t0 = 0;
    for (; t0 + 32 <= padded_targets; t0 += 32) balance_blocks<4, F8>(g, nn, nv, g_targets, t0, jacobian, d);
    switch ((padded_targets - t0) / 8) {
    case 3: balance_blocks<3, F8>(g, nn, nv, g_targets, t0, jacobian, d); break;
    case 2: balance_blocks<2, F8>(g, nn, nv, g_targets, t0, jacobian, d); break;
    case 1: balance_blocks<1, F8>(g, nn, nv, g_targets, t0, jacobian, d); break;
    default: break;
    }
}

MVPT_MULTI_ISA void selection_kernel(const float *__restrict g, float g0, const int32_t *__restrict slot,
                                     const uint64_t *__restrict keys, uint64_t hash, size_t n, bool jacobian,
                                     float *__restrict s_sel, uint32_t *__restrict selected) {
    for (size_t i = 0; i < n; ++i) {
        const float r = g0 / g[i];
        const float s_j = select(g[i] > 0.f, select(r < 1.f, r, 1.f), 0.f); // jacobian_similarity(g0, g[i])
        const float s = select(jacobian, s_j, 1.f);
        const float u = bits_to_unit_float(uint32_t(mix_bits(hash + keys[slot[i]])));
        s_sel[i] = s;
        selected[i] = u < s;
    }
}

} // namespace

uint32_t shift_status(const MvVertex &y, bool depth_ok, const ShiftGeometry &g, const SampleWindow &window,
                      uint32_t *pixel) {
    return status_of(y, depth_ok, g, window.x0, window.y0, window.x1, window.y1, pixel);
}

void shift_static_views(const ProjectionTable &table, const FilmTable &films, const MvVertex &y, ViewShifts &out) {
    const size_t n = table.size();
    out.resize(n);
    ShiftBatch &b = out.geo;
    shift_kernel(table.data(), films.x0.data(), films.y0.data(), films.x1.data(), films.y1.data(), n, y,
                 b.film_x.data(), b.film_y.data(), b.lens_x.data(), b.lens_y.data(), b.lens_z.data(),
                 b.density.data(), b.visible_length.data(), out.status.data(), out.pixel.data());
}

void MvCandidates::reserve(size_t views) {
    views = whole_lanes(views + 1); // the segment loop reads one entry past whole_lanes(size - 1)
    if (slot.size() >= views) return;
    slot.resize(views);
    pixel.resize(views);
    film.resize(views);
    for (auto *v : {&g, &n, &lx, &ly, &lz, &vis}) v->resize(views);
    wi.resize(views);
}

void viewing_directions(MvCandidates &c, Point3f p, const Frame &frame) {
    direction_kernel(c.lx.data(), c.ly.data(), c.lz.data(), whole_lanes(c.size), p, frame, c.wi.data());
}

void visibility_segments(const MvCandidates &c, Point3f o, Point3f y, float *dx, float *dy, float *dz, float *t_max) {
    const size_t n = c.size - 1, padded = whole_lanes(n);
    segment_kernel(c.lx.data() + 1, c.ly.data() + 1, c.lz.data() + 1, c.vis.data() + 1, padded, o, y, dx, dy, dz, t_max);
    std::fill(t_max + n, t_max + padded, -1.f); // the padding is not traced
}

void select_by_jacobian(const MvCandidates &c, const uint64_t *slot_keys, uint64_t sample_hash, bool jacobian,
                        float *s_sel, uint32_t *selected) {
    if (c.size < 2) return;
    selection_kernel(c.g.data() + 1, c.g[0], c.slot.data() + 1, slot_keys, sample_hash, c.size - 1, jacobian,
                     s_sel + 1, selected + 1);
}

void balance_sums(const float *g, const float *n, size_t valid, const float *g_targets, size_t padded_targets,
                  bool jacobian, float *d) {
    balance_kernel(g, n, valid, g_targets, padded_targets, jacobian, d);
}

} // namespace mvpt
