// `gridvolume`: a voxel grid from a Mitsuba `.vol` file mapped onto the unit cube [0, 1]^3
// of its `to_world` (or, with `use_grid_bbox`, onto the box the file declares), read with
// trilinear or nearest filtering, voxel centres at (i + 1/2) / resolution; lookups beyond the
// outer voxels, inside the cube or outside it, follow `wrap_mode` (clamp, repeat, mirror), as
// Mitsuba 3's texture does. (A heterogeneous medium is empty outside its extinction's cube.)
#include "../../core/transform.h"
#include "../../core/plugin.h"
#include "../../io/vol_reader.h"
#include "../volume.h"

namespace mvpt {

namespace {

class GridVolume final : public Volume {
public:
    GridVolume(const Properties &props, const LoadContext &ctx) {
        m_grid = read_vol(ctx.resolve(props.get_string("filename"), props.loc()), props.loc());
        std::string filter = props.get_string("filter_type", "trilinear");
        if (filter != "trilinear" && filter != "nearest")
            props.fail("filter_type", "filter_type must be 'trilinear' or 'nearest', got '" + filter + "'");
        m_trilinear = filter == "trilinear";
        std::string wrap = props.get_string("wrap_mode", "clamp");
        if (wrap == "clamp") m_wrap = Wrap::Clamp;
        else if (wrap == "repeat") m_wrap = Wrap::Repeat;
        else if (wrap == "mirror") m_wrap = Wrap::Mirror;
        else props.fail("wrap_mode", "wrap_mode must be 'clamp', 'repeat' or 'mirror', got '" + wrap + "'");
        props.get_bool("raw", false);  // colour conversions of grids only apply to spectral rendering
        props.get_bool("accel", true); // Mitsuba's choice of texture lookup code
        Transform to_world = props.get_transform("to_world");
        if (props.get_bool("use_grid_bbox", false)) {
            Vec3f extent = m_grid.box_max - m_grid.box_min;
            if (!(extent.x > 0.f && extent.y > 0.f && extent.z > 0.f))
                props.fail("use_grid_bbox", "the grid's own bounding box is empty");
            to_world = to_world * Transform::translate(Vec3f(m_grid.box_min)) * Transform::scale(extent);
        }
        m_to_local = to_world.inverse();
        for (float v : m_grid.values) m_max = std::max(m_max, v), m_min = std::min(m_min, v);
        for (int i = 0; i < 8; ++i)
            m_bounds.expand(to_world.point(Point3f(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1))));
    }

    Spectrum eval(Point3f p_world) const override {
        Point3f f;
        if (!voxel_coords(p_world, f)) return Spectrum(0.f);
        if (!m_trilinear) return voxel(int(std::floor(f.x + 0.5f)), int(std::floor(f.y + 0.5f)), int(std::floor(f.z + 0.5f)));
        const int x0 = int(std::floor(f.x)), y0 = int(std::floor(f.y)), z0 = int(std::floor(f.z));
        return trilinear(x0, y0, z0, Vec3f(f.x - float(x0), f.y - float(y0), f.z - float(z0)));
    }
    MajorantGrid majorant_grid() const override;
    ValueBounds segment_bounds(Point3f a, Point3f b) const override;
    bool refines_bounds() const override { return true; }
    float max_value() const override { return m_max; }
    float min_value() const override { return m_min; }
    BoundingBox bounds() const override { return m_bounds; }
    int channels() const override { return m_grid.channels; }

private:
    enum class Wrap { Clamp, Repeat, Mirror };

    /// Voxel coordinates of world point `p` (voxel i's centre at i), false where not finite.
    bool voxel_coords(Point3f p_world, Point3f &f) const {
        const Point3f p = m_to_local.point(p_world);
        if (!all_finite(p)) return false;
        // (Bounded so that far points convert to int safely; float has no fraction left there.)
        auto coord = [](float u, int n) { return std::clamp(u * float(n) - 0.5f, -1e7f, 1e7f); };
        f = Point3f(coord(p.x, m_grid.nx), coord(p.y, m_grid.ny), coord(p.z, m_grid.nz));
        return true;
    }
    /// The trilinear interpolation at offset `t` in [0, 1]^3 from voxel (x0, y0, z0).
    Spectrum trilinear(int x0, int y0, int z0, Vec3f t) const {
        Spectrum r(0.f);
        for (int corner = 0; corner < 8; ++corner) {
            const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
            const float w = (dx ? t.x : 1.f - t.x) * (dy ? t.y : 1.f - t.y) * (dz ? t.z : 1.f - t.z);
            r += voxel(x0 + dx, y0 + dy, z0 + dz) * w;
        }
        return r;
    }
    /// Bounds over the box [lo, hi] of voxel coordinates inside the cell between the centres
    /// of voxels `j` and j + 1: the interpolation is multilinear there, so its extremes lie at
    /// the box's corners.
    ValueBounds corner_bounds(const int j[3], Point3f lo, Point3f hi) const;
    /// Bounds over voxels [i0, i1] (each axis, wrapped); none known past 4 voxels an axis.
    ValueBounds voxel_range_bounds(const int i0[3], const int i1[3]) const;
    /// The greatest channel of each voxel, reduced to majorant cells of k voxels' cells along
    /// `axis` (cell c spanning voxels c k - 1 to c k + k - 1, wrapped).
    std::vector<float> reduce_axis(const std::vector<float> &in, int dims[3], int axis, int k, int cells) const;

    /// Index i of a row of n voxels, wrapped into [0, n).
    int wrap(int i, int n) const {
        switch (m_wrap) {
            case Wrap::Repeat: return ((i % n) + n) % n;
            case Wrap::Mirror: {
                int m = ((i % (2 * n)) + 2 * n) % (2 * n);
                return m < n ? m : 2 * n - 1 - m;
            }
            default: return std::clamp(i, 0, n - 1);
        }
    }

    Spectrum voxel(int x, int y, int z) const {
        x = wrap(x, m_grid.nx), y = wrap(y, m_grid.ny), z = wrap(z, m_grid.nz);
        const float *v = &m_grid.values[((size_t(z) * size_t(m_grid.ny) + size_t(y)) * size_t(m_grid.nx) + size_t(x)) *
                                        size_t(m_grid.channels)];
        return m_grid.channels == 1 ? Spectrum(v[0]) : Spectrum(v[0], v[1], v[2]);
    }

    VolumeGrid m_grid;
    Transform m_to_local;
    bool m_trilinear = true;
    Wrap m_wrap = Wrap::Clamp;
    float m_max = 0.f, m_min = 0.f;  // the bounds of its values and of 0 (outside the grid)
    BoundingBox m_bounds;
};


// The majorant cells lie on the dual lattice of the voxel centres: a cell between the centres
// of voxels i - 1 and i along each axis bounds a trilinear lookup there by its 8 corner voxels
// (after the wrap mode), and a nearest one too; the half cells between the cube's faces and the
// outer centres take their wrapped neighbours. A grid of n voxels has n + 1 such cells an axis;
// past MaxMajorantCells, cells span k of them (the refinement along rays, MajorantWalk, makes up
// for the looser bounds).
constexpr int MaxMajorantCells = 64;

MajorantGrid GridVolume::majorant_grid() const {
    const int n[3] = {m_grid.nx, m_grid.ny, m_grid.nz};
    MajorantGrid g;
    int k[3], dims[3] = {n[0], n[1], n[2]};
    for (int a = 0; a < 3; ++a) {
        k[a] = (n[a] + MaxMajorantCells) / MaxMajorantCells;
        g.res[a] = (n[a] + k[a]) / k[a];
    }
    std::vector<float> m(size_t(n[0]) * size_t(n[1]) * size_t(n[2]));
    for (size_t i = 0; i < m.size(); ++i) {
        const float *v = &m_grid.values[i * size_t(m_grid.channels)];
        m[i] = m_grid.channels == 1 ? v[0] : std::max({v[0], v[1], v[2]});
    }
    for (int a = 0; a < 3; ++a) m = reduce_axis(m, dims, a, k[a], g.res[a]);
    g.values = std::move(m);
    // Grid coordinate (voxel coordinate + 1) / k: cell c starts at the centre of voxel c k - 1.
    const Vec3f per_voxel(1.f / float(k[0]), 1.f / float(k[1]), 1.f / float(k[2]));
    g.to_grid = Transform::translate(per_voxel * 0.5f) *
                Transform::scale(Vec3f(float(n[0]) * per_voxel.x, float(n[1]) * per_voxel.y, float(n[2]) * per_voxel.z)) *
                m_to_local;
    g.outside = m_max;
    return g;
}

std::vector<float> GridVolume::reduce_axis(const std::vector<float> &in, int dims[3], int axis, int k, int cells) const {
    const size_t stride = axis == 0 ? 1 : axis == 1 ? size_t(dims[0]) : size_t(dims[0]) * size_t(dims[1]);
    const size_t outer = in.size() / (stride * size_t(dims[axis]));
    const int n = dims[axis];
    std::vector<float> out(outer * size_t(cells) * stride, 0.f);
    for (size_t o = 0; o < outer; ++o)
        for (int c = 0; c < cells; ++c)
            for (int i = c * k - 1; i <= std::min(c * k + k - 1, n); ++i) {
                const float *src = &in[(o * size_t(n) + size_t(wrap(i, n))) * stride];
                float *dst = &out[(o * size_t(cells) + size_t(c)) * stride];
                for (size_t s = 0; s < stride; ++s) dst[s] = std::max(dst[s], src[s]);
            }
    dims[axis] = cells;
    return out;
}

ValueBounds GridVolume::segment_bounds(Point3f a, Point3f b) const {
    Point3f fa, fb;
    if (!voxel_coords(a, fa) || !voxel_coords(b, fb)) return {};
    const Point3f lo = vmin(fa, fb), hi = vmax(fa, fb);
    int i0[3], i1[3];
    if (m_trilinear) {
        bool one_cell = true;
        for (int c = 0; c < 3; ++c) {
            i0[c] = int(std::floor(lo[c])), i1[c] = int(std::floor(hi[c])) + 1;
            one_cell &= hi[c] <= float(i0[c] + 1);
        }
        if (one_cell) return corner_bounds(i0, lo, hi);
    } else {
        for (int c = 0; c < 3; ++c) i0[c] = int(std::floor(lo[c] + 0.5f)), i1[c] = int(std::floor(hi[c] + 0.5f));
    }
    return voxel_range_bounds(i0, i1);
}

ValueBounds GridVolume::corner_bounds(const int j[3], Point3f lo, Point3f hi) const {
    ValueBounds r{Infinity, 0.f, true};
    for (int corner = 0; corner < 8; ++corner) {
        Vec3f t;
        for (int c = 0; c < 3; ++c)
            t[c] = std::clamp(((corner >> c) & 1 ? hi[c] : lo[c]) - float(j[c]), 0.f, 1.f);
        const Spectrum v = trilinear(j[0], j[1], j[2], t);
        r.lo = std::min(r.lo, v.mean()), r.hi = std::max(r.hi, v.max_value());
    }
    return r;
}

ValueBounds GridVolume::voxel_range_bounds(const int i0[3], const int i1[3]) const {
    for (int c = 0; c < 3; ++c)
        if (i1[c] - i0[c] >= 4) return {};
    ValueBounds r{Infinity, 0.f};
    for (int z = i0[2]; z <= i1[2]; ++z)
        for (int y = i0[1]; y <= i1[1]; ++y)
            for (int x = i0[0]; x <= i1[0]; ++x) {
                const Spectrum v = voxel(x, y, z);
                r.lo = std::min(r.lo, v.mean()), r.hi = std::max(r.hi, v.max_value());
            }
    return r;
}

} // namespace

MVPT_REGISTER_PLUGIN("volume", "gridvolume", [](const Properties &p, const LoadContext &ctx) {
    return std::make_shared<GridVolume>(p, ctx);
});

} // namespace mvpt
