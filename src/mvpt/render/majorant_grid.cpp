#include "majorant_grid.h"

namespace mvpt {

MajorantGrid MajorantGrid::uniform(float bound) {
    MajorantGrid g;
    g.outside = bound;
    return g;
}

void MajorantGrid::scale(float s) {
    for (float &v : values) v *= s;
    outside *= s;
}

MajorantDDA::MajorantDDA(const MajorantGrid &grid, const Ray &ray, float t0, float t1)
    : m_grid(grid), m_t(t0), m_t1(t1) {
    if (!grid.has_cells()) {
        m_phase = Phase::After;
        return;
    }
    m_o = grid.to_grid.point(ray.o);
    const Vec3f d = m_d = grid.to_grid.vector(ray.d);
    // Slab test against the box [0, res) of the cells.
    m_box_t0 = t0, m_box_t1 = t1;
    for (int a = 0; a < 3; ++a) {
        m_step[a] = d[a] > 0.f ? 1 : d[a] < 0.f ? -1 : 0;
        m_inv_d[a] = m_step[a] != 0 ? 1.f / d[a] : Infinity;
        if (m_step[a] == 0) {
            if (!(m_o[a] >= 0.f && m_o[a] <= float(grid.res[a]))) m_box_t1 = -Infinity; // parallel, outside
            continue;
        }
        float near = -m_o[a] * m_inv_d[a], far = (float(grid.res[a]) - m_o[a]) * m_inv_d[a];
        if (near > far) std::swap(near, far);
        m_box_t0 = std::max(m_box_t0, near), m_box_t1 = std::min(m_box_t1, far);
    }
    if (!(m_box_t0 < m_box_t1)) m_phase = Phase::After;
}

void MajorantDDA::enter_cells() {
    for (int a = 0; a < 3; ++a) {
        const float p = m_step[a] != 0 ? m_o[a] + m_box_t0 * m_d[a] : m_o[a];
        m_cell[a] = std::clamp(int(std::floor(std::clamp(p, -1.f, float(m_grid.res[a])))), 0, m_grid.res[a] - 1);
        m_t_next[a] = m_step[a] != 0 ? (float(m_cell[a] + (m_step[a] > 0)) - m_o[a]) * m_inv_d[a] : Infinity;
    }
    m_phase = Phase::Cells;
}

bool MajorantDDA::next(float &t_end, float &bound) {
    if (m_phase == Phase::Before) {
        if (m_box_t0 > m_t) {
            t_end = m_box_t0, bound = m_grid.outside;
            m_t = t_end;
            enter_cells();
            return true;
        }
        enter_cells();
    }
    if (m_phase == Phase::Cells) {
        const int a = m_t_next[0] <= m_t_next[1] ? (m_t_next[0] <= m_t_next[2] ? 0 : 2) : (m_t_next[1] <= m_t_next[2] ? 1 : 2);
        bound = m_grid.at(m_cell[0], m_cell[1], m_cell[2]);
        t_end = std::max(m_t, std::min(m_t_next[a], m_box_t1));
        m_cell[a] += m_step[a];
        // The last cell reaches the box's exit, whatever rounding says of its faces.
        if (t_end >= m_box_t1 || m_cell[a] < 0 || m_cell[a] >= m_grid.res[a]) {
            t_end = std::max(m_t, m_box_t1);
            m_phase = Phase::After;
        } else {
            m_t_next[a] = (float(m_cell[a] + (m_step[a] > 0)) - m_o[a]) * m_inv_d[a];
        }
        m_t = t_end;
        return true;
    }
    if (m_phase == Phase::After && m_t < m_t1) {
        t_end = m_t1, bound = m_grid.outside;
        m_t = t_end;
        m_phase = Phase::Done;
        return true;
    }
    m_phase = Phase::Done;
    return false;
}

} // namespace mvpt
