// Visibility of a static camera rig from cells of the scene: a multi-view native sample
// traces a segment from its vertex y to every candidate camera (§3 test 5 of the design
// doc). When no occluder can meet any segment from a cell of space to the hull of the rig's
// lens points, every bundle that leaves from that cell is unblocked: one proof, cached per
// cell, serves all the samples whose vertices lie in it, instead of a test (or a trace) per
// sample. The proof ignores the primitive y lies on (a segment leaves it on its camera
// side), so cells are keyed by (cell, that primitive).
#pragma once

#include "segment_cull.h"

#include <atomic>
#include <memory>
#include <vector>

namespace mvpt {

class RigVisibility {
public:
    /// `lens_points`: points whose convex hull holds every lens point of every view (for a
    /// thin lens, the corners of the square around its disk); `across` orients the bounds of
    /// a cell's segments (a row of the rig). `cells`: finest grid cells along the occluders' longest side.
    RigVisibility(const OccluderBvh &occluders, const std::vector<Point3f> &lens_points, Vec3f across, int cells = 128);
    ~RigVisibility();

    /// True when no occluder can block a segment from `o` (a vertex offset off its surface
    /// on the side of the lens points it is shifted to) to a lens point of the rig. `own`:
    /// the occluder the vertex lies on (OccluderBvh::occluder_of). False when that cannot be
    /// shown (`o` outside the grid, an occluder in the way, or `own` not usable as a key).
    bool unblocked(Point3f o, int64_t own) const;
    /// The same for a vertex on primitive `prim` of `shape`.
    bool unblocked(Point3f o, const Shape *shape, uint32_t prim) const {
        return unblocked(o, m_occ.occluder_of(shape, prim));
    }

    /// Keys evaluated so far (each costs one tree query; a key is evaluated once).
    size_t evaluated() const { return m_evaluated.load(std::memory_order_relaxed); }

private:
    /// The proof for one key (exact in double precision up to OccluderBvh's margin).
    /// The proof for the cell `idx` of size 2^shift finest cells.
    bool evaluate(const int64_t idx[3], int shift, int64_t own) const;

    const OccluderBvh &m_occ;
    /// The corners of a box around the lens points (in the rig's frame), and its centre.
    double m_rig[8][3], m_rig_centre[3];
    double m_across[3];
    /// The finest grid: origin, cell size, cells per axis.
    double m_lo[3], m_size;
    float m_lo_f[3], m_inv_size_f;
    int m_dims[3];
    /// Per occluder: whether it may serve as a key (spheres; triangles of at least a quarter
    /// of a cell's face: the smaller triangles of fine meshes would fill the cache for no reuse).
    std::vector<uint8_t> m_keyed;
    /// Open-addressing table of ((key + 1) << 1 | unblocked), 0 = empty; results are pure
    /// functions of the key, so races only ever store the same value.
    static constexpr size_t TableBits = 20, MaxProbes = 32;
    /// Grid levels: cells of 4, 2 and 1 finest cells a side, tried coarse first.
    static constexpr int Levels = 3;
    std::unique_ptr<std::atomic<uint64_t>[]> m_table;
    mutable std::atomic<size_t> m_evaluated{0};
};

} // namespace mvpt
