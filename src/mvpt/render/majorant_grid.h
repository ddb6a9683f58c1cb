// Majorant grids: piecewise-constant upper bounds of a volume (its largest channel) on a
// grid of cells, and the 3D DDA that walks the cells a ray crosses [Amanatides and Woo 1987],
// so that delta and ratio tracking can run against a local bound instead of the global
// maximum (pbrt-v4's majorant grid; Mitsuba 3's supergrid).
#pragma once

#include "../core/transform.h"

#include <vector>

namespace mvpt {

/// Bounds of a volume: cells [i, i + 1) x [j, j + 1) x [k, k + 1) of grid space, which
/// `to_grid` maps world points to, each with a value at least that of every point in it; beyond
/// the box [0, res) of the cells, `outside`. With no cells (res 0), `outside` holds everywhere.
struct MajorantGrid {
    int res[3] = {0, 0, 0};
    Transform to_grid;
    std::vector<float> values; ///< x fastest, then y, then z
    float outside = 0.f;

    /// One bound everywhere.
    static MajorantGrid uniform(float bound);
    float at(int x, int y, int z) const {
        return values[(size_t(z) * size_t(res[1]) + size_t(y)) * size_t(res[0]) + size_t(x)];
    }
    bool has_cells() const { return res[0] > 0 && res[1] > 0 && res[2] > 0; }
    /// Every bound times `s` (a medium's `scale`).
    void scale(float s);
};

/// The pieces of a ray's parameter range [t0, t1) over which a majorant grid is constant, in
/// order: before its box, each cell crossed, after it. The ray's parameter is kept (grid space
/// is an affine image of world space), so pieces are world distances along a unit direction.
class MajorantDDA {
public:
    MajorantDDA(const MajorantGrid &grid, const Ray &ray, float t0, float t1);
    /// The next piece [t, t_end) (t: where the previous one ended) and its bound; false past t1.
    bool next(float &t_end, float &bound);

private:
    /// Enters the cell phase: the cell at the box entry and the next face crossings.
    void enter_cells();

    const MajorantGrid &m_grid;
    Point3f m_o;
    Vec3f m_d, m_inv_d;
    float m_t = 0.f, m_t1 = 0.f, m_box_t0 = 0.f, m_box_t1 = 0.f;
    int m_cell[3] = {0, 0, 0}, m_step[3] = {0, 0, 0};
    float m_t_next[3] = {0.f, 0.f, 0.f};
    enum class Phase { Before, Cells, After, Done } m_phase = Phase::Before;
};

} // namespace mvpt
