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
        Point3f p = m_to_local.point(p_world);
        if (!all_finite(p)) return Spectrum(0.f);
        // (Bounded so that far points convert to int safely; float has no fraction left there.)
        auto coord = [](float u, int n) { return std::clamp(u * float(n) - 0.5f, -1e7f, 1e7f); };
        const float fx = coord(p.x, m_grid.nx), fy = coord(p.y, m_grid.ny), fz = coord(p.z, m_grid.nz);
        if (!m_trilinear) return voxel(int(std::floor(fx + 0.5f)), int(std::floor(fy + 0.5f)), int(std::floor(fz + 0.5f)));
        const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy)), z0 = int(std::floor(fz));
        const float tx = fx - float(x0), ty = fy - float(y0), tz = fz - float(z0);
        Spectrum r(0.f);
        for (int corner = 0; corner < 8; ++corner) {
            const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
            const float w = (dx ? tx : 1.f - tx) * (dy ? ty : 1.f - ty) * (dz ? tz : 1.f - tz);
            r += voxel(x0 + dx, y0 + dy, z0 + dz) * w;
        }
        return r;
    }
    float max_value() const override { return m_max; }
    float min_value() const override { return m_min; }
    BoundingBox bounds() const override { return m_bounds; }
    int channels() const override { return m_grid.channels; }

private:
    enum class Wrap { Clamp, Repeat, Mirror };

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

} // namespace

MVPT_REGISTER_PLUGIN("volume", "gridvolume", [](const Properties &p, const LoadContext &ctx) {
    return std::make_shared<GridVolume>(p, ctx);
});

} // namespace mvpt
