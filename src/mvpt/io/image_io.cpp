#include "image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image_write.h>
#define STB_IMAGE_IMPLEMENTATION
// Only the formats whose truncation is caught (stb's readers fill a cut file with zeros): PNG
// by its chunk lengths, JPEG, HDR and BMP by the checks below. Not TGA or PNM.
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_ONLY_HDR
#define STBI_ONLY_BMP
// stb_image copies an empty PNG chunk with memcpy(NULL, src, 0) (stbi__getn), which
// UndefinedBehaviorSanitizer's nonnull check rejects; exempt stb's own functions from that one
// check (clang, the fuzzing build), not ours.
#if defined(__clang__)
#pragma clang attribute push(__attribute__((no_sanitize("nonnull-attribute"))), apply_to = function)
#endif
#include <stb_image.h>
#if defined(__clang__)
#pragma clang attribute pop
#endif

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <unistd.h>

namespace mvpt {

namespace fs = std::filesystem;

fs::path temp_path_for(const fs::path &path) {
    static std::atomic<unsigned> counter{0};
    return path.parent_path() / ("." + path.filename().string() + ".tmp" + std::to_string(getpid()) + "_" +
                                 std::to_string(counter++));
}

void commit_file(const fs::path &tmp, const fs::path &path) {
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw std::runtime_error("cannot write '" + path.string() + "'");
    }
}

void write_exr(const fs::path &path, int width, int height, const std::vector<ExrChannel> &channels) {
    fs::path tmp = temp_path_for(path);
    try {
        Imf::Header header(width, height);
        header.compression() = Imf::ZIP_COMPRESSION;
        Imf::FrameBuffer fb;
        for (const ExrChannel &c : channels) {
            if (c.data.size() != size_t(width) * height) throw std::runtime_error("channel '" + c.name + "' has the wrong size");
            header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
            fb.insert(c.name, Imf::Slice(Imf::FLOAT, (char *)c.data.data(), sizeof(float), sizeof(float) * width));
        }
        {
            Imf::OutputFile file(tmp.c_str(), header);
            file.setFrameBuffer(fb);
            file.writePixels(height);
        }
        commit_file(tmp, path);
    } catch (const std::exception &e) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw std::runtime_error("cannot write EXR '" + path.string() + "': " + e.what());
    }
}

void write_png_srgb(const fs::path &path, int width, int height, const float *rgb) {
    std::vector<unsigned char> px(size_t(width) * height * 3);
    for (size_t i = 0; i < px.size(); ++i) px[i] = (unsigned char)std::lround(srgb_encode(rgb[i]) * 255.f);
    // Encoded in memory, then written with every error checked (stb's file writer ignores
    // them: a full disk left an empty PNG).
    std::string png;
    auto append = [](void *out, void *data, int size) { static_cast<std::string *>(out)->append((char *)data, size_t(size)); };
    if (!stbi_write_png_to_func(append, &png, width, height, 3, px.data(), width * 3))
        throw std::runtime_error("cannot encode PNG '" + path.string() + "'");
    fs::path tmp = temp_path_for(path);
    std::FILE *f = std::fopen(tmp.c_str(), "wb");
    bool ok = f && std::fwrite(png.data(), 1, png.size(), f) == png.size() && std::fflush(f) == 0;
    const std::string why = ok ? "" : std::strerror(errno);
    if (f && std::fclose(f) != 0 && ok) ok = false;
    if (!ok) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw std::runtime_error("cannot write PNG '" + path.string() + "'" + (why.empty() ? "" : ": " + why));
    }
    commit_file(tmp, path);
}

namespace {
/// Empty if the Radiance HDR file `data` holds every scanline its header promises, otherwise
/// what is missing (stb_image reads past a truncated file's end as if it had data).
std::string radiance_incomplete(const std::string &data) {
    size_t pos = data.find("\n\n");
    if (pos == std::string::npos) return "no end of header";
    pos += 2;
    const size_t eol = data.find('\n', pos);
    if (eol == std::string::npos) return "no resolution line";
    char a[3] = {}, b[3] = {};
    long n1 = 0, n2 = 0;
    if (std::sscanf(data.substr(pos, eol - pos).c_str(), "%2s %ld %2s %ld", a, &n1, b, &n2) != 4 || n1 <= 0 || n2 <= 0)
        return "a bad resolution line";
    const long lines = n1, width = n2; // scanlines run along the second axis
    size_t p = eol + 1;
    auto at = [&](size_t k) { return (unsigned char)data[p + k]; };
    for (long y = 0; y < lines; ++y) {
        const bool rle = width >= 8 && width < 32768 && p + 4 <= data.size() && at(0) == 2 && at(1) == 2 &&
                         ((long(at(2)) << 8) | at(3)) == width;
        if (!rle) { // flat: four bytes per pixel
            if (data.size() - p < size_t(width) * 4) return "scanline " + std::to_string(y + 1) + " of " + std::to_string(lines);
            p += size_t(width) * 4;
            continue;
        }
        p += 4;
        for (int c = 0; c < 4; ++c)
            for (long x = 0; x < width;) {
                if (p >= data.size()) return "scanline " + std::to_string(y + 1) + " of " + std::to_string(lines);
                const unsigned count = (unsigned char)data[p++];
                const long run = count > 128 ? long(count) - 128 : long(count);
                if (run == 0 || x + run > width) return "a bad run in scanline " + std::to_string(y + 1);
                const size_t bytes = count > 128 ? 1 : size_t(run);
                if (data.size() - p < bytes) return "scanline " + std::to_string(y + 1) + " of " + std::to_string(lines);
                p += bytes;
                x += run;
            }
    }
    return {};
}

/// Empty if the JPEG file `data` is whole, otherwise why not. Its entropy-coded data stuffs every
/// 0xFF byte, so a marker there is a real one: a whole file has an end-of-image marker (FF D9)
/// after its last start-of-scan (FF DA); stb_image decodes a cut one with the rest left grey.
std::string jpeg_incomplete(const std::string &data) {
    const size_t sos = data.rfind("\xFF\xDA");
    if (sos == std::string::npos) return "no image data";
    if (data.find("\xFF\xD9", sos) == std::string::npos) return "no end of image after its last scan";
    return {};
}

/// Empty if the uncompressed BMP file `data` holds every row its header promises, otherwise what
/// is missing (stb_image reads no compressed BMP).
std::string bmp_incomplete(const std::string &data) {
    auto le = [&](size_t at, int bytes) {
        int64_t v = 0;
        for (int k = bytes - 1; k >= 0; --k) v = (v << 8) | (unsigned char)data[at + k];
        return v;
    };
    if (data.size() < 26) return "no header";
    const int64_t offset = le(10, 4), core = le(14, 4) == 12;
    if (!core && data.size() < 34) return "no header";
    const int64_t width = core ? le(18, 2) : le(18, 4), bits = core ? le(24, 2) : le(28, 2);
    int64_t height = core ? le(20, 2) : le(22, 4);
    if (!core && height >= (int64_t(1) << 31)) height = (int64_t(1) << 32) - height; // top-down rows
    if (!core && le(30, 4) != 0 && le(30, 4) != 3) return {}; // compressed: stb_image refuses it
    const int64_t most = int64_t(1) << 24; // stb_image refuses larger sides, as other bad headers
    if (width <= 0 || width > most || height <= 0 || height > most || bits > 32) return {};
    const int64_t stride = (bits * width + 31) / 32 * 4;
    if (int64_t(data.size()) < offset + stride * height)
        return std::to_string(data.size()) + " bytes, fewer than the " + std::to_string(offset + stride * height) +
               " its rows take";
    return {};
}

/// Refuses a file in which a check above found `missing` (empty: the file is whole).
void require_whole(const std::string &missing, const char *format) {
    if (!missing.empty())
        throw std::runtime_error(std::string("cannot read image: a truncated or corrupt ") + format + " file (" +
                                 missing + ")");
}

std::string read_file_bytes(const fs::path &path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error(std::string("cannot open the file: ") + std::strerror(errno));
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
} // namespace

ImageRGB read_image(const fs::path &path, bool raw, size_t max_pixels) {
    ImageRGB img;
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".exr") {
        // Read R, G, B (or a single Y) as 32-bit floats, whatever the stored type.
        try {
            Imf::InputFile file(path.c_str());
            const Imath::Box2i dw = file.header().dataWindow();
            img.width = dw.max.x - dw.min.x + 1;
            img.height = dw.max.y - dw.min.y + 1;
            const Imf::ChannelList &cl = file.header().channels();
            bool rgb = cl.findChannel("R") && cl.findChannel("G") && cl.findChannel("B");
            if (!rgb && !cl.findChannel("Y")) throw std::runtime_error("no R, G, B or Y channels");
            if (!file.isComplete()) throw std::runtime_error("the file is truncated (pixel blocks are missing)");
            size_t n = size_t(img.width) * img.height;
            if (n > max_pixels)
                throw std::runtime_error(std::to_string(img.width) + " x " + std::to_string(img.height) +
                                         " pixels, more than the " + std::to_string(max_pixels) + " an image may have");
            img.rgb.assign(3 * n, 0.f);
            Imf::FrameBuffer fb;
            const char *names[3] = {"R", "G", "B"};
            for (int c = 0; c < (rgb ? 3 : 1); ++c) // Slice::Make offsets by the data window's origin
                fb.insert(rgb ? names[c] : "Y", Imf::Slice::Make(Imf::FLOAT, img.rgb.data() + c, dw, 3 * sizeof(float),
                                                                 3 * sizeof(float) * img.width));
            file.setFrameBuffer(fb);
            file.readPixels(dw.min.y, dw.max.y);
            if (!rgb)
                for (size_t i = 0; i < n; ++i) img.rgb[3 * i + 1] = img.rgb[3 * i + 2] = img.rgb[3 * i];
        } catch (const std::exception &e) {
            throw std::runtime_error(std::string("cannot read EXR: ") + e.what());
        }
        return img;
    }
    const std::string data = read_file_bytes(path);
    const auto *bytes = reinterpret_cast<const stbi_uc *>(data.data());
    const int size = int(std::min(data.size(), size_t(INT_MAX)));
    int w, h, n;
    if (stbi_info_from_memory(bytes, size, &w, &h, &n) && size_t(w) * size_t(h) > max_pixels)
        throw std::runtime_error("cannot read image: " + std::to_string(w) + " x " + std::to_string(h) +
                                 " pixels, more than the " + std::to_string(max_pixels) + " an image may have");
    if (ext == ".hdr") {
        require_whole(radiance_incomplete(data), "Radiance HDR");
        float *d = stbi_loadf_from_memory(bytes, size, &w, &h, &n, 3);
        if (!d) throw std::runtime_error(std::string("cannot read image: ") + stbi_failure_reason());
        img.rgb.assign(d, d + size_t(w) * h * 3);
        stbi_image_free(d);
    } else {
        if (data.compare(0, 2, "\xFF\xD8") == 0) require_whole(jpeg_incomplete(data), "JPEG");
        if (data.compare(0, 2, "BM") == 0) require_whole(bmp_incomplete(data), "BMP");
        unsigned char *d = stbi_load_from_memory(bytes, size, &w, &h, &n, 3);
        if (!d) throw std::runtime_error(std::string("cannot read image: ") + stbi_failure_reason());
        img.rgb.resize(size_t(w) * h * 3);
        for (size_t i = 0; i < img.rgb.size(); ++i) {
            float v = d[i] / 255.f;
            img.rgb[i] = raw ? v : srgb_decode(v);
        }
        stbi_image_free(d);
    }
    img.width = w;
    img.height = h;
    return img;
}

} // namespace mvpt
