// Whether any two views can share a native sample in time (views_share_in_time, §3 test 1):
// when none can, multi-view path tracing renders the views by path tracing.
#include "mvpt/integrators/multiview/mv_shift.h"

#include <gtest/gtest.h>

using namespace mvpt;

namespace {
// Views of shutter [t0, t0 + dt]; the camera is only read for a timed view facing an instant
// in a still scene, which these cases avoid.
std::vector<MvView> views(std::initializer_list<std::pair<float, float>> shutters) {
    std::vector<MvView> v;
    for (auto [t0, dt] : shutters) v.push_back({nullptr, uint32_t(v.size()), t0, dt});
    return v;
}
} // namespace

TEST(MvShift, OneViewSharesNothing) {
    EXPECT_FALSE(views_share_in_time(views({{0.f, 1.f}}), false));
    EXPECT_FALSE(views_share_in_time(views({{0.f, 0.f}}), true));
}

TEST(MvShift, StillScenesShareBetweenAnyShutters) {
    // The affine time map pairs every two timed shutters, however far apart.
    EXPECT_TRUE(views_share_in_time(views({{0.f, 1.f / 24}, {5.f, 1.f / 24}}), false));
    EXPECT_TRUE(views_share_in_time(views({{0.f, 0.f}, {3.f, 0.f}}), false));
    // Three views: two of them are of one kind (instant or timed).
    EXPECT_TRUE(views_share_in_time(views({{0.f, 0.f}, {1.f, 0.5f}, {2.f, 0.f}}), false));
}

TEST(MvShift, MovingShapesShareOnlyOverlappingShutters) {
    const float f = 1.f / 24;
    // A shot's frames with a shutter of one frame time touch but do not overlap.
    EXPECT_FALSE(views_share_in_time(views({{0.f, f}, {f, f}, {2 * f, f}, {3 * f, f}}), true));
    EXPECT_FALSE(views_share_in_time(views({{3 * f, 0.5f * f}, {0.f, 0.5f * f}, {f, 0.5f * f}}), true));
    // A shutter of 1.5 frame times overlaps the next frame's.
    EXPECT_TRUE(views_share_in_time(views({{0.f, 1.5f * f}, {f, 1.5f * f}}), true));
    // Out of order, the overlap found all the same; a long shutter spanning a later short one.
    EXPECT_TRUE(views_share_in_time(views({{2.f, 0.1f}, {0.f, 5.f}, {1.f, 0.1f}}), true));
    // Instants share only with the same instant; never with a shutter of length.
    EXPECT_TRUE(views_share_in_time(views({{0.5f, 0.f}, {1.f, 0.f}, {0.5f, 0.f}}), true));
    EXPECT_FALSE(views_share_in_time(views({{0.5f, 0.f}, {0.f, 1.f}}), true));
    EXPECT_FALSE(views_share_in_time(views({{0.5f, 0.f}, {0.75f, 0.f}}), true));
}
