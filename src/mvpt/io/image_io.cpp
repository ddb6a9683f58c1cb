#include "image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <ImfArray.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image_write.h>
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

#include <algorithm>
#include <atomic>
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
    fs::path tmp = temp_path_for(path);
    if (!stbi_write_png(tmp.c_str(), width, height, 3, px.data(), width * 3)) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw std::runtime_error("cannot write PNG '" + path.string() + "'");
    }
    commit_file(tmp, path);
}

ImageRGB read_image(const fs::path &path, bool raw) {
    ImageRGB img;
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".exr") {
        try {
            // Full float precision (Imf::RgbaInputFile would round every value to half).
            Imf::InputFile file(path.c_str());
            Imath::Box2i dw = file.header().dataWindow();
            img.width = dw.max.x - dw.min.x + 1;
            img.height = dw.max.y - dw.min.y + 1;
            const Imf::ChannelList &channels = file.header().channels();
            bool rgb = channels.findChannel("R") && channels.findChannel("G") && channels.findChannel("B");
            if (!rgb && !channels.findChannel("Y")) throw std::runtime_error("no R, G, B or Y channels");
            img.rgb.assign(size_t(img.width) * img.height * 3, 0.f);
            const size_t xs = 3 * sizeof(float), ys = xs * img.width;
            char *base = (char *)img.rgb.data() - (dw.min.x * xs + dw.min.y * ys);
            Imf::FrameBuffer fb;
            if (rgb) {
                for (int c = 0; c < 3; ++c)
                    fb.insert(std::string(1, "RGB"[c]), Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys));
                file.setFrameBuffer(fb);
                file.readPixels(dw.min.y, dw.max.y);
            } else {
                fb.insert("Y", Imf::Slice(Imf::FLOAT, base, xs, ys));
                file.setFrameBuffer(fb);
                file.readPixels(dw.min.y, dw.max.y);
                for (size_t i = 0; i < img.rgb.size(); i += 3) img.rgb[i + 1] = img.rgb[i + 2] = img.rgb[i];
            }
        } catch (const std::exception &e) {
            throw std::runtime_error(std::string("cannot read EXR: ") + e.what());
        }
        return img;
    }
    int w, h, n;
    if (ext == ".hdr") {
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
