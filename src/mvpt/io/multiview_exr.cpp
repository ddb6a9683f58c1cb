#include "multiview_exr.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputPart.h>
#include <ImfMultiPartInputFile.h>
#include <ImfMultiPartOutputFile.h>
#include <ImfOutputPart.h>
#include <ImfPartType.h>
#include <ImfStandardAttributes.h>

#include <algorithm>
#include <set>
#include <stdexcept>

namespace mvpt {

namespace fs = std::filesystem;

namespace {

void check_views(const std::vector<ExrView> &views) {
    if (views.empty()) throw std::runtime_error("no views");
    std::set<std::string> names;
    for (const ExrView &v : views) {
        if (v.name.empty()) throw std::runtime_error("a view has an empty name");
        if (!names.insert(v.name).second) throw std::runtime_error("two views are named '" + v.name + "'");
        if (v.width <= 0 || v.height <= 0) throw std::runtime_error("view '" + v.name + "' has no pixels");
        if (v.channels.empty()) throw std::runtime_error("view '" + v.name + "' has no channels");
        for (const ExrChannel &c : v.channels)
            if (c.data.size() != size_t(v.width) * v.height)
                throw std::runtime_error("channel '" + c.name + "' of view '" + v.name + "' has the wrong size");
    }
}

} // namespace

void write_multiview_exr(const fs::path &path, const std::vector<ExrView> &views) {
    fs::path tmp = temp_path_for(path);
    try {
        check_views(views);
        int max_w = 0, max_h = 0;
        Imf::StringVector names;
        for (const ExrView &v : views) {
            max_w = std::max(max_w, v.width);
            max_h = std::max(max_h, v.height);
            names.push_back(v.name);
        }
        const Imath::Box2i display(Imath::V2i(0, 0), Imath::V2i(max_w - 1, max_h - 1));
        std::vector<Imf::Header> headers;
        for (const ExrView &v : views) {
            Imf::Header h(display, Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(v.width - 1, v.height - 1)));
            h.compression() = Imf::ZIP_COMPRESSION;
            h.setName(v.name);
            h.setType(Imf::SCANLINEIMAGE);
            h.setView(v.name);
            Imf::addMultiView(h, names);
            for (const ExrChannel &c : v.channels) h.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
            headers.push_back(std::move(h));
        }
        {
            Imf::MultiPartOutputFile file(tmp.c_str(), headers.data(), int(headers.size()));
            for (size_t p = 0; p < views.size(); ++p) {
                const ExrView &v = views[p];
                Imf::FrameBuffer fb;
                for (const ExrChannel &c : v.channels)
                    fb.insert(c.name, Imf::Slice(Imf::FLOAT, (char *)c.data.data(), sizeof(float), sizeof(float) * v.width));
                Imf::OutputPart part(file, int(p));
                part.setFrameBuffer(fb);
                part.writePixels(v.height);
            }
        }
        commit_file(tmp, path);
    } catch (const std::exception &e) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw std::runtime_error("cannot write multi-view EXR '" + path.string() + "': " + e.what());
    }
}

std::vector<ExrView> read_multiview_exr(const fs::path &path) {
    try {
        Imf::MultiPartInputFile file(path.c_str());
        std::vector<ExrView> views;
        for (int p = 0; p < file.parts(); ++p) {
            const Imf::Header &h = file.header(p);
            if (h.hasType() && h.type() != Imf::SCANLINEIMAGE && h.type() != Imf::TILEDIMAGE)
                throw std::runtime_error("part " + std::to_string(p) + " holds deep data");
            ExrView v;
            v.name = h.hasView() ? h.view() : h.hasName() ? h.name() : std::to_string(p);
            const Imath::Box2i dw = h.dataWindow();
            v.width = dw.max.x - dw.min.x + 1;
            v.height = dw.max.y - dw.min.y + 1;
            const size_t n = size_t(v.width) * v.height;
            for (auto c = h.channels().begin(); c != h.channels().end(); ++c) v.channels.push_back({c.name(), std::vector<float>(n)});
            Imf::FrameBuffer fb;
            for (ExrChannel &c : v.channels) {
                char *base = (char *)c.data.data() - (ptrdiff_t(dw.min.x) + ptrdiff_t(dw.min.y) * v.width) * ptrdiff_t(sizeof(float));
                fb.insert(c.name, Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * v.width));
            }
            Imf::InputPart part(file, p);
            part.setFrameBuffer(fb);
            part.readPixels(dw.min.y, dw.max.y);
            views.push_back(std::move(v));
        }
        return views;
    } catch (const std::exception &e) {
        throw std::runtime_error("cannot read EXR '" + path.string() + "': " + e.what());
    }
}

} // namespace mvpt
