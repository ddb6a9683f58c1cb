// Reading image files: an EXR whose data window does not start at the origin reads its pixels
// in order; a truncated EXR or JPEG, a format mvpt does not read and a header that claims more
// than MaxImagePixels are refused.
#include "mvpt/io/image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#include "test_dirs.h"

#include <stb_image_write.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace mvpt;
namespace fs = std::filesystem;

namespace {

/// A one-channel ("Y") EXR of w x h pixels whose data window starts at `origin`, pixel i = i.
void write_y_exr(const fs::path &path, Imath::V2i origin, int w, int h) {
    const Imath::Box2i dw(origin, origin + Imath::V2i(w - 1, h - 1));
    Imf::Header header(Imath::Box2i({0, 0}, {w - 1, h - 1}), dw);
    header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
    std::vector<float> y(size_t(w) * h);
    for (size_t i = 0; i < y.size(); ++i) y[i] = float(i);
    Imf::FrameBuffer fb;
    fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, y.data(), dw));
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(h);
}

std::string read_error(const fs::path &path) {
    try {
        read_image(path);
    } catch (const std::exception &e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST(ImageIo, ExrDataWindowAwayFromTheOrigin) {
    for (Imath::V2i origin : {Imath::V2i(0, 0), Imath::V2i(-3, -2), Imath::V2i(5, 7)}) {
        const fs::path p = fresh_test_dir("mvpt_image_io_tests") / "window.exr";
        write_y_exr(p, origin, 4, 3);
        const ImageRGB img = read_image(p);
        ASSERT_EQ(img.width, 4);
        ASSERT_EQ(img.height, 3);
        for (int i = 0; i < 12; ++i)
            for (int c = 0; c < 3; ++c) EXPECT_EQ(img.rgb[3 * i + c], float(i)) << "origin " << origin << " pixel " << i;
    }
}

TEST(ImageIo, TruncatedExrIsRefused) {
    const fs::path p = fresh_test_dir("mvpt_image_io_tests") / "cut.exr";
    write_y_exr(p, {0, 0}, 64, 64);
    fs::resize_file(p, fs::file_size(p) / 2);
    EXPECT_NE(read_error(p).find("cannot read EXR"), std::string::npos);
}

TEST(ImageIo, HeaderClaimingTooManyPixelsIsRefused) {
    // A Radiance header of 20000 x 20000 pixels with no data: refused by its size, before any
    // allocation, whatever else is wrong with it.
    const fs::path p = fresh_test_dir("mvpt_image_io_tests") / "huge.hdr";
    std::ofstream(p, std::ios::binary) << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 20000 +X 20000\n";
    const std::string what = read_error(p);
    EXPECT_NE(what.find("20000 x 20000 pixels, more than"), std::string::npos) << what;
}

TEST(ImageIo, CallerBoundOnPixels) {
    // A caller's lower bound (the fuzz target's) refuses an image the default bound reads.
    const fs::path p = fresh_test_dir("mvpt_image_io_tests") / "bound.exr";
    write_y_exr(p, {0, 0}, 4, 3);
    EXPECT_EQ(read_image(p, false, 12).width, 4);
    try {
        read_image(p, false, 11);
        ADD_FAILURE() << "a 4 x 3 image read under a bound of 11 pixels";
    } catch (const std::exception &e) {
        EXPECT_NE(std::string(e.what()).find("4 x 3 pixels, more than the 11"), std::string::npos) << e.what();
    }
}

TEST(ImageIo, TruncatedJpegIsRefused) {
    const fs::path p = fresh_test_dir("mvpt_image_io_tests") / "cut.jpg";
    std::vector<unsigned char> px(64 * 64 * 3);
    for (size_t i = 0; i < px.size(); ++i) px[i] = (unsigned char)(i * 7);
    ASSERT_TRUE(stbi_write_jpg(p.c_str(), 64, 64, 3, px.data(), 90));
    EXPECT_EQ(read_image(p).width, 64);
    fs::resize_file(p, fs::file_size(p) - 200);
    const std::string what = read_error(p);
    EXPECT_NE(what.find("truncated or corrupt JPEG file"), std::string::npos) << what;
}

TEST(ImageIo, TgaIsRefused) {
    // stb_image reads a cut TGA as zeros: a 6399 x 25088 one in 27 bytes (a fuzzer's find).
    const fs::path p = fresh_test_dir("mvpt_image_io_tests") / "cut.png";
    const unsigned char tga[] = {1, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0x18, 0, 0x62, 32, 0, 0};
    std::ofstream(p, std::ios::binary).write((const char *)tga, sizeof tga);
    EXPECT_NE(read_error(p).find("cannot read image"), std::string::npos);
}

TEST(ImageIo, TruncatedBmpIsRefused) {
    const fs::path p = fresh_test_dir("mvpt_image_io_tests") / "cut.bmp";
    std::vector<unsigned char> px(5 * 4 * 3, 200);
    ASSERT_TRUE(stbi_write_bmp(p.c_str(), 5, 4, 3, px.data()));
    const ImageRGB img = read_image(p);
    EXPECT_EQ(img.width, 5);
    EXPECT_EQ(img.height, 4);
    fs::resize_file(p, fs::file_size(p) - 1);
    const std::string what = read_error(p);
    EXPECT_NE(what.find("truncated or corrupt BMP file"), std::string::npos) << what;
}
