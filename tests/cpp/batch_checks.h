// Checks shared by the tests of batched code against its one-at-a-time counterpart.
#pragma once

#include "mvpt/integrators/path.h"
#include "mvpt/scene/scene.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace mvpt::test {

/// Whether a and b hold the same bytes (so +0 differs from -0 and NaNs compare by payload).
template <typename T> bool same_bits(const T &a, const T &b) { return std::memcmp(&a, &b, sizeof(T)) == 0; }

/// trace_batch of `rays` from `states` equals trace of each path bit for bit, valid flags
/// included (gtest failures otherwise); returns how many paths carried light.
inline size_t expect_trace_batch_equals_trace(const Scene &scene, const PathIntegrator &integrator,
                                              const std::vector<Ray> &rays, const std::vector<PathState> &states,
                                              const std::vector<Sampler> &samplers) {
    std::vector<Sampler> batch_samplers = samplers, ref_samplers = samplers;
    std::vector<Spectrum> batch(rays.size());
    std::vector<uint8_t> valid(rays.size(), 7);
    RayCounters counters;
    integrator.trace_batch(scene, rays.data(), states.data(), batch_samplers.data(), batch.data(), valid.data(),
                           rays.size(), counters);
    size_t nonzero = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        bool ref_valid = true;
        Spectrum ref = integrator.trace(scene, rays[i], states[i], ref_samplers[i], counters, nullptr, &ref_valid);
        nonzero += !ref.is_black();
        EXPECT_EQ(bool(valid[i]), ref_valid) << "path " << i;
        EXPECT_TRUE(same_bits(batch[i], ref)) << "path " << i << ": batch " << batch[i].r << " " << batch[i].g << " "
                                              << batch[i].b << ", trace " << ref.r << " " << ref.g << " " << ref.b;
        if (::testing::Test::HasFailure()) break; // the first difference says enough
    }
    return nonzero;
}

} // namespace mvpt::test
