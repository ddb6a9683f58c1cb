// gather_lambert_lanes (integrators/path/lane_gather.cpp): the Lambertian kernels' input columns
// gathered from the wavefront's records, by the AVX-512 loop and by the scalar one, against
// the records' fields themselves.
#include "mvpt/integrators/path/lane_gather.h"
#include "mvpt/integrators/path/path_kernels.h"
#include "mvpt/render/interaction.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

using namespace mvpt;

namespace {

struct Records {
    std::vector<SurfaceInteraction> si;
    std::vector<Ray> rays;
    std::vector<WavePath> paths;
    std::vector<ScatterVertex> scatter;
    std::vector<float> u[7];
    const float *u_ptr[7];
};

/// `n` paths and vertices with distinct pseudo-random field values.
Records make_records(size_t n) {
    Records r;
    uint32_t state = 7u;
    auto rnd = [&state] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) * 0x1p-24f - 0.5f;
    };
    auto vec = [&] { return Vec3f(rnd(), rnd(), rnd()); };
    r.si.resize(n);
    r.rays.resize(n);
    r.paths.resize(n);
    r.scatter.resize(n);
    for (size_t i = 0; i < n; ++i) {
        SurfaceInteraction &s = r.si[i];
        s.p = vec(), s.n = vec(), s.wi = vec(); // wi: not read for Lambertian lanes
        s.sh_frame = Frame(vec(), vec(), vec());
        r.rays[i] = Ray{vec(), vec(), 0.f, Infinity, 0.f};
        if (i % 5 == 0) r.rays[i].d.y = 0.f; // a signed zero in -d
        if (i % 7 == 3) { // all-zero terms: the sign of WiZ's zero shows how -d was formed
            r.rays[i].d = Vec3f(0.f, 0.f, 0.f);
            s.sh_frame.n = Vec3f(0.5f, 0.25f, 0.125f);
        }
        WavePath &p = r.paths[i];
        p.throughput = Spectrum(rnd(), rnd(), rnd());
        p.eta = rnd();
        p.depth = uint32_t(i % 7);
        r.scatter[i].refl = Color3f(rnd(), rnd(), rnd());
        LightSample &ls = r.scatter[i].emitter_sample.first;
        ls.p = vec(), ls.n = vec(), ls.d = vec();
        ls.dist = rnd(), ls.pdf = rnd(), ls.delta = i % 3 == 0;
        r.scatter[i].emitter_sample.second = Spectrum(rnd(), rnd(), rnd());
    }
    for (size_t c = 0; c < 7; ++c) {
        r.u[c].resize(n);
        for (float &x : r.u[c]) x = rnd();
        r.u_ptr[c] = r.u[c].data();
    }
    return r;
}

} // namespace

TEST(LaneGather, LambertLanesCopyTheirRecords) {
    constexpr size_t records = 200, stride = 64;
    Records r = make_records(records);
    const LaneSources src{r.si.data(), r.rays.data(), r.paths.data(), r.scatter.data(), r.u_ptr, 4};
    for (size_t n : {size_t(64), size_t(37), size_t(5)}) { // whole and partial 16-lane steps
        std::vector<uint32_t> path(n), vertex(n);
        for (size_t m = 0; m < n; ++m) path[m] = uint32_t((m * 53 + 11) % records), vertex[m] = uint32_t((m * 17 + 3) % records);
        for (bool light : {true, false}) {
            std::vector<float> vec(lam_col::Count * stride, -7.f), scal(lam_col::Count * stride, -7.f);
            gather_lambert_lanes(vec.data(), stride, n, path.data(), vertex.data(), src, light, true);
            gather_lambert_lanes(scal.data(), stride, n, path.data(), vertex.data(), src, light, false);
            for (size_t c = 0; c < lam_col::Count; ++c)
                for (size_t m = 0; m < stride; ++m)
                    ASSERT_EQ(std::bit_cast<uint32_t>(vec[c * stride + m]), std::bit_cast<uint32_t>(scal[c * stride + m]))
                        << "n " << n << " column " << c << " lane " << m;
            using namespace lam_col;
            for (size_t m = 0; m < n; ++m) {
                const SurfaceInteraction &si = r.si[path[m]];
                const WavePath &p = r.paths[path[m]];
                const uint32_t j = vertex[m];
                auto at = [&](size_t c) { return vec[c * stride + m]; };
                // -ray.d in the shading frame, as the emission loop would set wi.
                EXPECT_EQ(std::bit_cast<uint32_t>(at(WiZ)), std::bit_cast<uint32_t>(si.to_local(-r.rays[path[m]].d).z));
                EXPECT_EQ(at(Sy), si.sh_frame.s.y);
                EXPECT_EQ(at(Tz), si.sh_frame.t.z);
                EXPECT_EQ(at(Nx), si.sh_frame.n.x);
                EXPECT_EQ(at(Py), si.p.y);
                EXPECT_EQ(at(Gz), si.n.z);
                EXPECT_EQ(at(Rg), r.scatter[j].refl.g);
                EXPECT_EQ(at(Bb), p.throughput.b);
                EXPECT_EQ(at(Eta), p.eta);
                EXPECT_EQ(at(RrOn), p.depth + 1 >= 4 ? 1.f : 0.f);
                EXPECT_EQ(at(URr), r.u[6][j]);
                EXPECT_EQ(at(DirUx), r.u[4][j]);
                EXPECT_EQ(at(DirUy), r.u[5][j]);
                EXPECT_EQ(at(LightUx), light ? r.u[1][j] : -7.f);
                EXPECT_EQ(at(LightUy), light ? r.u[2][j] : -7.f);
                EXPECT_EQ(at(TwoSided), -7.f); // left to the caller
                EXPECT_EQ(at(Emitter), -7.f);
            }
        }
    }
}

TEST(LaneGather, LambertNeeLanesCopyTheirRecords) {
    constexpr size_t records = 150, stride = 64;
    Records r = make_records(records);
    const LaneSources src{r.si.data(), r.rays.data(), r.paths.data(), r.scatter.data(), r.u_ptr, 4};
    for (size_t n : {size_t(64), size_t(23)}) {
        std::vector<uint32_t> path(n), vertex(n);
        for (size_t m = 0; m < n; ++m) path[m] = uint32_t((m * 41 + 5) % records), vertex[m] = uint32_t((m * 13 + 1) % records);
        std::vector<float> vec(ln_col::Count * stride, -7.f), scal(ln_col::Count * stride, -7.f);
        gather_lambert_nee_lanes(vec.data(), stride, n, path.data(), vertex.data(), src, true);
        gather_lambert_nee_lanes(scal.data(), stride, n, path.data(), vertex.data(), src, false);
        for (size_t c = 0; c < ln_col::Count; ++c)
            for (size_t m = 0; m < stride; ++m)
                ASSERT_EQ(std::bit_cast<uint32_t>(vec[c * stride + m]), std::bit_cast<uint32_t>(scal[c * stride + m]))
                    << "n " << n << " column " << c << " lane " << m;
        using namespace ln_col;
        size_t deltas = 0;
        for (size_t m = 0; m < n; ++m) {
            const SurfaceInteraction &si = r.si[path[m]];
            const ScatterVertex &v = r.scatter[vertex[m]];
            const LightSample &ls = v.emitter_sample.first;
            auto at = [&](size_t c) { return vec[c * stride + m]; };
            EXPECT_EQ(std::bit_cast<uint32_t>(at(WiZ)), std::bit_cast<uint32_t>(si.to_local(-r.rays[path[m]].d).z));
            EXPECT_EQ(at(Ny), si.sh_frame.n.y);
            EXPECT_EQ(at(Pz), si.p.z);
            EXPECT_EQ(at(Gx), si.n.x);
            EXPECT_EQ(at(Rb), v.refl.b);
            EXPECT_EQ(at(Bg), r.paths[path[m]].throughput.g);
            EXPECT_EQ(at(Ldz), ls.d.z);
            EXPECT_EQ(at(Lpx), ls.p.x);
            EXPECT_EQ(at(LDist), ls.dist);
            EXPECT_EQ(at(LPdf), ls.pdf);
            EXPECT_EQ(at(LDelta), ls.delta ? 1.f : 0.f);
            EXPECT_EQ(at(Wg), v.emitter_sample.second.g);
            EXPECT_EQ(at(TwoSided), -7.f); // left to the caller
            deltas += ls.delta;
        }
        EXPECT_GT(deltas, 0u);
        EXPECT_LT(deltas, n);
    }
}

TEST(LaneGather, ShadowRaysOfTheLanesThatCountAppendInOrder) {
    constexpr size_t records = 100, stride = 64, o0 = 5, start = 3;
    Records r = make_records(records);
    for (size_t i = 0; i < records; ++i) r.si[i].time = 0.25f + float(i);
    auto value = [](size_t m, size_t q) { return float(m) + 0.01f * float(q + 1); };
    for (size_t n : {size_t(64), size_t(29), size_t(1)}) {
        std::vector<float> cols((o0 + 11) * stride);
        std::vector<uint32_t> path(stride);
        size_t counting = 0;
        for (size_t m = 0; m < stride; ++m) {
            path[m] = uint32_t((m * 31 + 7) % records);
            for (size_t q = 0; q < 10; ++q) cols[(o0 + q) * stride + m] = value(m, q);
            // Whether the lane counts: > 0 only (NaN, zero and negative values do not).
            const float ok[] = {1.f, 0.f, std::nanf(""), -1.f, 0.5f};
            cols[(o0 + 10) * stride + m] = ok[m % 5];
            counting += m < n && (m % 5 == 0 || m % 5 == 4);
        }
        std::vector<float> shadow_v[8], shadow_s[8];
        float *sv[8], *ss[8];
        for (size_t q = 0; q < 8; ++q) {
            shadow_v[q].assign(start + stride + 16, -3.f), shadow_s[q].assign(start + stride + 16, -3.f);
            sv[q] = shadow_v[q].data(), ss[q] = shadow_s[q].data();
        }
        std::vector<PendingShadow> pend_v(start + stride + 16), pend_s(start + stride + 16);
        const size_t cv = append_shadow_rays(cols.data(), stride, n, o0, path.data(), r.si.data(), sv, pend_v.data(), start, true);
        const size_t cs = append_shadow_rays(cols.data(), stride, n, o0, path.data(), r.si.data(), ss, pend_s.data(), start, false);
        ASSERT_EQ(cv, start + counting);
        ASSERT_EQ(cs, cv);
        for (size_t q = 0; q < 8; ++q)
            for (size_t i = 0; i < cv; ++i) ASSERT_EQ(shadow_v[q][i], shadow_s[q][i]) << "column " << q << " entry " << i;
        for (size_t i = start; i < cv; ++i) {
            ASSERT_EQ(pend_v[i].path, pend_s[i].path) << i;
            ASSERT_EQ(pend_v[i].contribution.r, pend_s[i].contribution.r) << i;
            ASSERT_EQ(pend_v[i].contribution.g, pend_s[i].contribution.g) << i;
            ASSERT_EQ(pend_v[i].contribution.b, pend_s[i].contribution.b) << i;
        }
        // In lane order: entry start + e is the e-th lane that counts, its time its interaction's.
        size_t e = start;
        for (size_t m = 0; m < n; ++m) {
            if (!(m % 5 == 0 || m % 5 == 4)) continue;
            EXPECT_EQ(shadow_v[0][e], value(m, 0));
            EXPECT_EQ(shadow_v[6][e], value(m, 6));
            EXPECT_EQ(shadow_v[7][e], r.si[path[m]].time);
            EXPECT_EQ(pend_v[e].path, path[m]);
            EXPECT_EQ(pend_v[e].contribution.b, value(m, 9));
            ++e;
        }
        EXPECT_EQ(shadow_v[0][0], -3.f); // entries before `start` are kept
    }
}
