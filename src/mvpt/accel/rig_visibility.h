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

    /// Starts loading the table entries that unblocked(o, ...) will read (a hint, no effect on
    /// results): the table is far larger than the caches, and its random reads were about
    /// 5 % of a native sample's time on the glossy Cornell box.
    void prefetch(Point3f o, int64_t own) const;
    void prefetch(Point3f o, const Shape *shape, uint32_t prim) const {
        prefetch(o, m_occ.occluder_of(shape, prim));
    }

    /// Keys evaluated so far (each costs one tree query; a key is evaluated once).
    size_t evaluated() const { return m_evaluated.load(std::memory_order_relaxed); }

private:
    /// The finest cell holding `o`; false outside the grid.
    bool finest_cell(Point3f o, int64_t finest[3]) const;
    /// The table key of (the cell of grid `level` holding finest cell `finest`, occluder `own`),
    /// and that cell's index `idx` in its level's grid.
    uint64_t cell_key(const int64_t finest[3], int level, int64_t own, int64_t idx[3]) const;
    /// The proof for the cell `idx` of size 2^shift finest cells (exact in double precision up
    /// to OccluderBvh's margin).
    bool evaluate(const int64_t idx[3], int shift, int64_t own) const;
    /// Half-spaces that bound the segments from the cell [lo, hi] to the rig: a wedge around
    /// the axis from the cell to the rig, and caps along it.
    void add_wedge(const double lo[3], const double hi[3], ConvexRegion &r) const;
    /// The half-space above the plane of occluder `own` (the triangle that the segments start
    /// on), when the whole rig is strictly on one side of it.
    void add_own_plane(const double lo[3], const double hi[3], int64_t own, ConvexRegion &r) const;

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
    static constexpr uint64_t TableMask = (uint64_t(1) << TableBits) - 1;
    /// Grid levels: cells of 4, 2 and 1 finest cells a side, tried coarse first.
    static constexpr int Levels = 3;
    /// The table's memory (in huge pages where the system offers them).
    class TableMemory {
    public:
        TableMemory() = default;
        explicit TableMemory(size_t entries);
        TableMemory(const TableMemory &) = delete;
        TableMemory &operator=(TableMemory &&o) noexcept;
        ~TableMemory();
        std::atomic<uint64_t> &operator[](size_t i) const { return m_entries[i]; }

    private:
        std::atomic<uint64_t> *m_entries = nullptr;
        void *m_base = nullptr;
        size_t m_bytes = 0, m_mapped = 0;
    };
    TableMemory m_table;
    mutable std::atomic<size_t> m_evaluated{0};
};

} // namespace mvpt
