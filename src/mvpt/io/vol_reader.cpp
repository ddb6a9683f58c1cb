#include "vol_reader.h"

#include <bit>
#include <cstring>
#include <fstream>
#include <sstream>

namespace mvpt {

namespace {

template <typename T> T load_le(const char *p) {
    static_assert(std::endian::native == std::endian::little, "the .vol reader assumes a little-endian host");
    T v;
    std::memcpy(&v, p, sizeof(T));
    return v;
}

/// The most values a grid may hold (4 GiB of float32): a corrupt header must not allocate more.
constexpr uint64_t MaxValues = uint64_t(1) << 30;
constexpr size_t HeaderBytes = 3 + 1 + 4 + 4 * 3 + 4 + 6 * 4;

} // namespace

VolumeGrid read_vol(const std::filesystem::path &path, const FileLoc &loc) {
    auto fail = [&](const std::string &what) -> void {
        throw SceneError(loc, "volume grid '" + path.string() + "': " + what);
    };
    std::ifstream f(path, std::ios::binary);
    if (!f) fail("cannot be read");
    std::stringstream ss;
    ss << f.rdbuf();
    const std::string data = ss.str();
    if (data.size() < HeaderBytes) fail("shorter than a .vol header (" + std::to_string(HeaderBytes) + " bytes)");
    if (data.compare(0, 3, "VOL") != 0) fail("not a .vol file (expected the bytes 'VOL' first)");
    if (uint8_t(data[3]) != 3) fail("version " + std::to_string(uint8_t(data[3])) + " (expected 3)");
    const char *p = data.data() + 4;
    int32_t encoding = load_le<int32_t>(p);
    if (encoding != 1) fail("encoding " + std::to_string(encoding) + " (expected 1: float32)");
    VolumeGrid g;
    g.nx = load_le<int32_t>(p + 4), g.ny = load_le<int32_t>(p + 8), g.nz = load_le<int32_t>(p + 12);
    g.channels = load_le<int32_t>(p + 16);
    if (g.nx <= 0 || g.ny <= 0 || g.nz <= 0)
        fail("resolution " + std::to_string(g.nx) + "x" + std::to_string(g.ny) + "x" + std::to_string(g.nz) +
             " (expected positive)");
    if (g.channels != 1 && g.channels != 3) fail(std::to_string(g.channels) + " channels (expected 1 or 3)");
    float box[6];
    for (int i = 0; i < 6; ++i) box[i] = load_le<float>(p + 20 + 4 * i);
    g.box_min = Point3f(box[0], box[1], box[2]), g.box_max = Point3f(box[3], box[4], box[5]);
    // Each partial product checked: the full product of three 31-bit counts can wrap past 2^64.
    uint64_t count = uint64_t(g.nx) * uint64_t(g.ny);
    if (count > MaxValues || (count *= uint64_t(g.nz)) > MaxValues || (count *= uint64_t(g.channels)) > MaxValues)
        fail("more than 2^30 values");
    if (data.size() != HeaderBytes + 4 * count)
        fail(std::to_string(data.size() - HeaderBytes) + " bytes of data (expected " + std::to_string(4 * count) +
             " for the resolution and channels in its header)");
    g.values.resize(size_t(count));
    std::memcpy(g.values.data(), data.data() + HeaderBytes, 4 * count);
    for (float v : g.values)
        if (!std::isfinite(v)) fail("a value that is not finite");
    return g;
}

} // namespace mvpt
