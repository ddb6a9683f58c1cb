#include "image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image_write.h>
#define STB_IMAGE_IMPLEMENTATION
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
} // namespace

ImageRGB read_image(const fs::path &path, bool raw) {
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
            if (n > MaxImagePixels)
                throw std::runtime_error(std::to_string(img.width) + " x " + std::to_string(img.height) +
                                         " pixels, more than the " + std::to_string(MaxImagePixels) + " an image may have");
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
    int w, h, n;
    if (stbi_info(path.c_str(), &w, &h, &n) && size_t(w) * size_t(h) > MaxImagePixels)
        throw std::runtime_error("cannot read image: " + std::to_string(w) + " x " + std::to_string(h) +
                                 " pixels, more than the " + std::to_string(MaxImagePixels) + " an image may have");
    if (ext == ".hdr") {
        std::ifstream in(path, std::ios::binary);
        const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        if (const std::string missing = radiance_incomplete(data); !missing.empty())
            throw std::runtime_error("cannot read image: a truncated or corrupt Radiance HDR file (" + missing + ")");
        float *d = stbi_loadf(path.c_str(), &w, &h, &n, 3);
        if (!d) throw std::runtime_error(std::string("cannot read image: ") + stbi_failure_reason());
        img.rgb.assign(d, d + size_t(w) * h * 3);
        stbi_image_free(d);
    } else {
        unsigned char *d = stbi_load(path.c_str(), &w, &h, &n, 3);
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
