// Multi-view EXR: parts of different sizes round-trip with their names, view and
// multiView attributes; bad input fails without leaving a file behind.
#include "mvpt/io/multiview_exr.h"

#include <ImfMultiPartInputFile.h>
#include <ImfHeader.h>
#include <ImfStandardAttributes.h>

#include "test_dirs.h"

#include <gtest/gtest.h>

#include <filesystem>

using namespace mvpt;
namespace fs = std::filesystem;

namespace {

ExrView ramp(const std::string &name, int w, int h, float offset) {
    ExrView v{name, w, h, {{"R", {}}, {"G", {}}, {"B", {}}}};
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < w * h; ++i) v.channels[c].data.push_back(offset + float(i) + 0.25f * float(c));
    return v;
}

} // namespace

TEST(MultiviewExr, PartsRoundTripWithViewAttributes) {
    fs::path p = fresh_test_dir("mvpt_multiview_exr_tests") / "views.exr";
    std::vector<ExrView> views = {ramp("left", 5, 3, 0.f), ramp("right", 4, 6, 100.f), ramp("center", 2, 2, 7.f)};
    write_multiview_exr(p, views);

    Imf::MultiPartInputFile file(p.c_str());
    ASSERT_EQ(file.parts(), 3);
    for (int i = 0; i < 3; ++i) {
        const Imf::Header &h = file.header(i);
        EXPECT_EQ(h.name(), views[i].name);
        EXPECT_EQ(h.view(), views[i].name);
        ASSERT_TRUE(Imf::hasMultiView(h));
        EXPECT_EQ(Imf::multiView(h), (Imf::StringVector{"left", "right", "center"}));
        // the display window is shared by all parts: the largest width and height
        EXPECT_EQ(h.displayWindow().max, Imath::V2i(4, 5));
    }

    std::vector<ExrView> back = read_multiview_exr(p);
    ASSERT_EQ(back.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(back[i].name, views[i].name);
        EXPECT_EQ(back[i].width, views[i].width);
        EXPECT_EQ(back[i].height, views[i].height);
        // EXR stores channels sorted by name: B, G, R
        ASSERT_EQ(back[i].channels.size(), 3u);
        for (size_t c = 0; c < 3; ++c) {
            EXPECT_EQ(back[i].channels[c].name, views[i].channels[2 - c].name);
            EXPECT_EQ(back[i].channels[c].data, views[i].channels[2 - c].data);
        }
    }
}

TEST(MultiviewExr, SinglePartFilesReadAsOneView) {
    fs::path p = fresh_test_dir("mvpt_multiview_exr_tests") / "single.exr";
    write_exr(p, 2, 1, {{"R", {1, 2}}, {"G", {3, 4}}, {"B", {5, 6}}});
    std::vector<ExrView> back = read_multiview_exr(p);
    ASSERT_EQ(back.size(), 1u);
    EXPECT_EQ(back[0].name, "0");
    EXPECT_EQ(back[0].width, 2);
    EXPECT_EQ(back[0].channels[1].data, (std::vector<float>{3, 4}));
}

TEST(MultiviewExr, BadViewsFailCleanly) {
    fs::path dir = fresh_test_dir("mvpt_multiview_exr_tests");
    EXPECT_THROW(write_multiview_exr(dir / "empty.exr", {}), std::runtime_error);
    EXPECT_THROW(write_multiview_exr(dir / "dup.exr", {ramp("a", 1, 1, 0), ramp("a", 1, 1, 0)}), std::runtime_error);
    ExrView bad = ramp("b", 2, 2, 0);
    bad.channels[0].data.pop_back();
    EXPECT_THROW(write_multiview_exr(dir / "size.exr", {bad}), std::runtime_error);
    EXPECT_TRUE(fs::is_empty(dir));
}
