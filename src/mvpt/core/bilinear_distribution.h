// Piecewise-bilinear 2D density on [0,1]^2: the density of Mitsuba 3's
// Hierarchical2D (core/distr_2d.h, no conditioning parameters), which the
// envmap emitter samples. Values sit on a w x h vertex grid; each of the
// (w-1) x (h-1) patches interpolates its four corners bilinearly. A patch is chosen by
// alias tables (a row by its mass, then a patch of the row), its point by inverting the
// bilinear density with the numbers that choice leaves over.
#pragma once

#include "alias_table.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace mvpt {

/// Inverse CDF of the density proportional to lerp(t, a, b) on [0, 1]
/// (a, b >= 0): the positive root of (b - a) t^2 / 2 + a t = u (a + b) / 2,
/// in the cancellation-free form u (a + b) / (a + sqrt(lerp(u, a^2, b^2))).
inline float sample_linear(float u, float a, float b) {
    float denom = a + std::sqrt(lerp(u, a * a, b * b));
    return denom > 0.f ? std::min(u * (a + b) / denom, OneMinusEpsilon) : u;
}

class BilinearDistribution2D {
public:
    BilinearDistribution2D() = default;
    /// `values`: row-major, `w` x `h` non-negative vertex values (w, h >= 2).
    BilinearDistribution2D(const std::vector<float> &values, int w, int h) : m_w(w), m_h(h), m_values(values) {
        const int nx = w - 1, ny = h - 1;
        m_rows.resize(ny);
        std::vector<float> row_sums(ny), patch(nx);
        double total = 0;
        for (int y = 0; y < ny; ++y) {
            for (int x = 0; x < nx; ++x)
                patch[x] = 0.25f * (vertex(x, y) + vertex(x + 1, y) + vertex(x, y + 1) + vertex(x + 1, y + 1));
            m_rows[y].build(patch);
            row_sums[y] = float(m_rows[y].sum());
            total += m_rows[y].sum();
        }
        m_marginal.build(row_sums); // all zero (a black map): any patch, of density 0
        // Scale so the interpolant integrates to one over the unit square.
        float scale = total > 0 ? float(double(nx) * double(ny) / total) : 0.f;
        for (float &v : m_values) v *= scale;
    }

    /// Point in [0,1)^2 with density `*pdf` w.r.t. area of the unit square.
    Vec2f sample(Vec2f u, float *pdf) const { return sample(u, pdf, [](int, int) {}); }

    /// As above; `on_cell(x, y)` is called as soon as the patch is chosen, before its
    /// vertices are read (a caller can prefetch its own data of that patch meanwhile).
    template <typename OnCell> Vec2f sample(Vec2f u, float *pdf, OnCell &&on_cell) const {
        float uy, ux;
        size_t py = m_marginal.sample(u.y, &uy);
        size_t px = m_rows[py].sample(u.x, &ux);
        const int x = int(px), y = int(py);
        on_cell(x, y);
        return sample_in_cell(x, y, ux, uy, pdf);
    }

    /// Lanes per stage of `sample_batch` (its per-lane temporaries stay in L1).
    static constexpr size_t BatchChunk = 64;

    /// `sample` for `n` points at once (p[i], pdf[i] from u[i]), as stages over the lanes so
    /// that their independent table reads overlap instead of each point's chain of dependent
    /// cache misses (row table, then patch vertices) running alone. Each lane's arithmetic is
    /// `sample`'s; `on_cell(i, x, y)` is called when lane i's patch is chosen, a stage before
    /// its vertices are read.
    template <typename OnCell> void sample_batch(size_t n, const Vec2f *u, Vec2f *p, float *pdf, OnCell &&on_cell) const {
        uint32_t cell_y[BatchChunk], slot[BatchChunk], cell_x[BatchChunk];
        float uy[BatchChunk], ux[BatchChunk];
        for (size_t i0 = 0; i0 < n; i0 += BatchChunk) {
            const size_t m = std::min(BatchChunk, n - i0);
            // Stage 1: the rows, from the marginal (a small table, mostly cached), and the slot
            // of each row's table, fetched.
            for (size_t i = 0; i < m; ++i) {
                cell_y[i] = m_marginal.sample(u[i0 + i].y, &uy[i]);
                const AliasTable &row = m_rows[cell_y[i]];
                slot[i] = uint32_t(row.slot_of(u[i0 + i].x));
                __builtin_prefetch(row.entry(slot[i]));
            }
            // Stage 2: the columns, fetching the patches' vertices.
            for (size_t i = 0; i < m; ++i) {
                const uint32_t y = cell_y[i];
                cell_x[i] = m_rows[y].sample_from(slot[i], u[i0 + i].x, &ux[i]);
                on_cell(i0 + i, int(cell_x[i]), int(y));
                prefetch_cell(int(cell_x[i]), int(y));
            }
            // Stage 3: the points in their patches, as in `sample`.
            for (size_t i = 0; i < m; ++i) p[i0 + i] = sample_in_cell(int(cell_x[i]), int(cell_y[i]), ux[i], uy[i], &pdf[i0 + i]);
        }
    }

    /// Fetch the four vertices of patch (x, y) (read by `sample` and `pdf` in that patch).
    void prefetch_cell(int x, int y) const {
        const float *v0 = &m_values[size_t(y) * m_w + x];
        __builtin_prefetch(v0);
        __builtin_prefetch(v0 + 1);
        __builtin_prefetch(v0 + m_w);
        __builtin_prefetch(v0 + m_w + 1);
    }

    /// Density at `p` (clamped to the unit square).
    float pdf(Vec2f p) const {
        float px = std::clamp(p.x, 0.f, 1.f) * float(m_w - 1), py = std::clamp(p.y, 0.f, 1.f) * float(m_h - 1);
        int x = std::min(int(px), m_w - 2), y = std::min(int(py), m_h - 2);
        return bilerp(vertex(x, y), vertex(x + 1, y), vertex(x, y + 1), vertex(x + 1, y + 1), px - float(x), py - float(y));
    }

    bool empty() const { return m_marginal.size() == 0 || m_marginal.empty(); }

private:
    float vertex(int x, int y) const { return m_values[size_t(y) * m_w + x]; }
    /// The last step of `sample`: the point in patch (x, y) from the reused numbers ux, uy.
    Vec2f sample_in_cell(int x, int y, float ux, float uy, float *pdf) const {
        float v00 = vertex(x, y), v10 = vertex(x + 1, y), v01 = vertex(x, y + 1), v11 = vertex(x + 1, y + 1);
        // Marginal in y is linear between the row sums, then x given y is linear.
        float fy = sample_linear(uy, v00 + v10, v01 + v11);
        float fx = sample_linear(ux, lerp(fy, v00, v01), lerp(fy, v10, v11));
        *pdf = bilerp(v00, v10, v01, v11, fx, fy);
        return {(float(x) + fx) / float(m_w - 1), (float(y) + fy) / float(m_h - 1)};
    }
    static float bilerp(float v00, float v10, float v01, float v11, float fx, float fy) {
        return lerp(fy, lerp(fx, v00, v10), lerp(fx, v01, v11));
    }

    int m_w = 0, m_h = 0;
    /// Vertex values normalized so that the interpolant is a density.
    std::vector<float> m_values;
    std::vector<AliasTable> m_rows;
    AliasTable m_marginal;
};

} // namespace mvpt
