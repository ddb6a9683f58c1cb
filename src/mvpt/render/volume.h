// Volumes (Mitsuba 3's "volume"): a quantity defined over space, such as a medium's
// extinction or albedo. `constvolume` is one value everywhere; `gridvolume` a voxel grid.
#pragma once

#include "../core/math.h"
#include "../core/spectrum_rgb.h"
#include "../core/properties.h"
#include "majorant_grid.h"
#include "shape.h"

#include <memory>
#include <string>

namespace mvpt {

/// Bounds of a volume over a region: `hi` is at least the value of every point and channel
/// there, `lo` at most the mean of the channels at every point (infinite `hi`: none known).
/// `tight`: they are the extremes over the region (a region's parts have none looser).
struct ValueBounds {
    float lo = 0.f, hi = Infinity;
    bool tight = false;
};

class Volume : public Object {
public:
    /// The value at world point `p` (a one-channel volume repeats it in each channel).
    virtual Spectrum eval(Point3f p) const = 0;
    /// The largest value over every point and channel.
    virtual float max_value() const = 0;
    /// The smallest value over every point and channel.
    virtual float min_value() const = 0;
    /// Where the volume can be non-zero (unbounded for a constant).
    virtual BoundingBox bounds() const = 0;
    /// 1 or 3.
    virtual int channels() const = 0;
    /// Upper bounds of the value by region, for tracking against local majorants; the
    /// default: max_value() everywhere.
    virtual MajorantGrid majorant_grid() const { return MajorantGrid::uniform(max_value()); }
    /// Bounds of the value on the segment between world points `a` and `b`; the default knows
    /// none. Where `refines_bounds`, they tighten as the segment shrinks.
    virtual ValueBounds segment_bounds(Point3f a, Point3f b) const {
        (void)a, (void)b;
        return {};
    }
    virtual bool refines_bounds() const { return false; }
    /// True, with the value, for a constant volume.
    virtual bool constant(Spectrum &value) const { (void)value; return false; }
};

/// A volume of one value everywhere (`constvolume`).
std::shared_ptr<Volume> constant_volume(Spectrum value);

/// The volume parameter `name`: a nested or referenced `<volume name="...">`, or a constant
/// given as `<float>`, `<rgb>` or `<spectrum>` (read as `use`), or `def` when absent.
std::shared_ptr<Volume> get_volume(const Properties &props, const std::string &name, Color3f def, SpectrumUse use);

/// Fails the parameter `name` unless every value of `v` lies in [lo, hi] (`what` says why).
void check_volume_range(const Properties &props, const std::string &name, const Volume &v, float lo, float hi,
                        const char *what);

} // namespace mvpt
