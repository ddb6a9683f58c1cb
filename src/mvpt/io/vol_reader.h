// Mitsuba's binary `.vol` grids (Mitsuba 0.6 / 3 `gridvolume` data): "VOL", version 3, an
// encoding (1: float32), the resolution x, y, z and the channel count as int32, a bounding
// box of six float32, then x-fastest float32 values with the channels interleaved.
#pragma once

#include "../core/error.h"
#include "../core/math.h"

#include <filesystem>
#include <vector>

namespace mvpt {

struct VolumeGrid {
    int nx = 0, ny = 0, nz = 0, channels = 0;
    /// The box the file declares (Mitsuba 3 maps the grid to the unit cube instead, unless
    /// told to use this one).
    Point3f box_min, box_max;
    /// values[((z * ny + y) * nx + x) * channels + c]
    std::vector<float> values;
};

/// Read a grid; errors name the file, `loc` (the element that asked for it) and what was expected.
VolumeGrid read_vol(const std::filesystem::path &path, const FileLoc &loc);

} // namespace mvpt
