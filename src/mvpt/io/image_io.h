// Image files: OpenEXR (float channels) and 8-bit sRGB PNG, written atomically
// (to a temporary file in the same directory, then renamed).
#pragma once

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace mvpt {

/// One named float channel of `width*height` values, row-major.
struct ExrChannel {
    std::string name;
    std::vector<float> data;
};

void write_exr(const std::filesystem::path &path, int width, int height, const std::vector<ExrChannel> &channels);
/// Linear RGB (3 floats per pixel) -> sRGB-encoded 8-bit PNG.
void write_png_srgb(const std::filesystem::path &path, int width, int height, const float *rgb);

/// A float RGB image read from EXR, PNG, JPEG, HDR or BMP; PNG/JPEG/BMP are sRGB-decoded
/// to linear unless `raw` (for data textures such as roughness).
struct ImageRGB {
    int width = 0, height = 0;
    std::vector<float> rgb;
};
/// The most pixels an image file may have (16384 x 16384, 3 GiB as float RGB): a header that
/// claims more is refused before anything is allocated.
inline constexpr size_t MaxImagePixels = size_t(1) << 28;
/// `max_pixels` lowers that bound where a caller must stay small (the fuzz target: a 40 KiB EXR
/// may rightly decompress to 16384 x 16384 pixels, which takes a minute and gigabytes there).
ImageRGB read_image(const std::filesystem::path &path, bool raw = false, size_t max_pixels = MaxImagePixels);

/// Rename `tmp` onto `path` (same directory), removing `tmp` on failure.
void commit_file(const std::filesystem::path &tmp, const std::filesystem::path &path);
std::filesystem::path temp_path_for(const std::filesystem::path &path);

inline float srgb_encode(float v) {
    if (!(v > 0.f)) return 0.f;
    if (v >= 1.f) return 1.f;
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}
inline float srgb_decode(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }

} // namespace mvpt
