// Batched independent-sampler draws (core/sampler_batch.h) against the sampler itself:
// bit-identical numbers for every lane, including counts that are not a multiple of the
// vector width.
#include "mvpt/core/sampler.h"
#include "mvpt/core/sampler_batch.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

using namespace mvpt;

TEST(SamplerBatch, VertexDrawsMatchSampler) {
    for (size_t n : {0, 1, 7, 8, 9, 61, 256}) {
        std::vector<Sampler> samplers;
        std::vector<uint64_t> hash(n);
        std::vector<uint32_t> dim(n);
        std::vector<float> u[7];
        for (auto &v : u) v.resize(n);
        for (size_t i = 0; i < n; ++i) {
            Sampler s(SamplerKind::Independent, 3);
            s.start(uint32_t(i % 3), uint32_t(i), uint32_t(7 * i), uint32_t(i / 5));
            s.set_dimension(3 + 5 * uint32_t(i % 9));
            hash[i] = s.sample_hash();
            dim[i] = s.dimension();
            samplers.push_back(s);
        }
        float *const out[7] = {u[0].data(), u[1].data(), u[2].data(), u[3].data(), u[4].data(), u[5].data(), u[6].data()};
        independent_vertex_draws(hash.data(), dim.data(), n, out);
        for (size_t i = 0; i < n; ++i) {
            Sampler &s = samplers[i];
            float ref[7];
            ref[0] = s.next_1d();
            Vec2f a = s.next_2d();
            ref[1] = a.x, ref[2] = a.y;
            ref[3] = s.next_1d();
            Vec2f b = s.next_2d();
            ref[4] = b.x, ref[5] = b.y;
            ref[6] = s.next_1d();
            for (int k = 0; k < 7; ++k)
                ASSERT_EQ(std::memcmp(&u[k][i], &ref[k], sizeof(float)), 0) << "n " << n << ", lane " << i << ", number " << k;
        }
    }
}

TEST(SamplerBatch, StartDrawsMatchSampler) {
    // Both forms: one pixel row and sample index for all lanes, and per-lane pixels and indices.
    for (bool per_lane : {false, true})
        for (size_t n : {0, 1, 7, 8, 9, 61, 256}) {
            const uint32_t seed = 11, view = 4, row = 23, index = 5;
            std::vector<uint32_t> px(n), py(n), sample(n);
            for (size_t i = 0; i < n; ++i) {
                px[i] = uint32_t(3 * i + 1);
                py[i] = per_lane ? uint32_t(i % 13) : row;
                sample[i] = per_lane ? uint32_t(i / 3) : index;
            }
            std::vector<uint64_t> ph(n), sh(n);
            std::vector<float> u[5];
            for (auto &v : u) v.resize(n);
            float *const out[5] = {u[0].data(), u[1].data(), u[2].data(), u[3].data(), u[4].data()};
            if (per_lane)
                independent_start_draws(seed, view, px.data(), py.data(), sample.data(), n, ph.data(), sh.data(), out);
            else
                independent_start_draws(seed, view, px.data(), row, index, n, ph.data(), sh.data(), out);
            for (size_t i = 0; i < n; ++i) {
                Sampler s(SamplerKind::Independent, seed);
                s.start(view, px[i], py[i], sample[i]);
                ASSERT_EQ(sh[i], s.sample_hash()) << "lane " << i;
                const Vec2f a = s.next_2d(), b = s.next_2d();
                const float ref[5] = {a.x, a.y, b.x, b.y, s.next_1d()};
                for (int k = 0; k < 5; ++k)
                    ASSERT_EQ(std::memcmp(&u[k][i], &ref[k], sizeof(float)), 0)
                        << (per_lane ? "per lane" : "row") << ", n " << n << ", lane " << i << ", number " << k;
                // start_from with the batch's hashes continues exactly like the sampler.
                Sampler t(SamplerKind::Independent, seed);
                t.start_from(ph[i], sh[i], sample[i], 3);
                ASSERT_EQ(t.next_1d(), s.next_1d()) << "lane " << i;
            }
        }
}
