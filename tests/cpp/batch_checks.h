// Checks shared by the tests of batched code against its one-at-a-time counterpart.
#pragma once

#include "mvpt/core/warp.h"
#include "mvpt/integrators/path/path.h"
#include "mvpt/accel/scene.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace mvpt::test {

/// Whether a and b hold the same bytes (so +0 differs from -0 and NaNs compare by payload).
template <typename T> bool same_bits(const T &a, const T &b) { return std::memcmp(&a, &b, sizeof(T)) == 0; }

/// Camera rays of a `res`² pixel grid over view 0's film, `spp` samples each, with their samplers.
/// `sobol` replaces the sensor's sampler by the Sobol sampler; `seed` is the samplers' seed.
inline void camera_rays(const Scene &scene, int res, int spp, std::vector<Ray> &rays, std::vector<Sampler> &samplers,
                        bool sobol = false, uint32_t seed = 7) {
    const Camera &cam = *scene.cameras()[0];
    for (int s = 0; s < spp; ++s)
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                Sampler sampler(sobol ? SamplerKind::Sobol : cam.sampler_kind, seed);
                sampler.start(0, uint32_t(x), uint32_t(y), uint32_t(s));
                sampler.set_dimension(DimFilm);
                Vec2f u_film = sampler.next_2d(), u_lens = sampler.next_2d();
                float u_time = sampler.next_1d();
                Vec2f film_pos((x + u_film.x) * cam.film.width / res, (y + u_film.y) * cam.film.height / res);
                Vec2f lens = cam.lens_radius() > 0.f ? warp::square_to_uniform_disk_concentric(u_lens) : Vec2f(0.f, 0.f);
                rays.push_back(cam.generate_ray(film_pos, lens, cam.sample_time(u_time)));
                samplers.push_back(sampler);
            }
}

/// li_batch of `rays` equals li of each ray bit for bit (gtest failures otherwise); returns how
/// many paths carried light, and li's radiance of each path in `li_out` if given.
inline size_t expect_li_batch_equals_li(const Scene &scene, const PathIntegrator &integrator,
                                        const std::vector<Ray> &rays, const std::vector<Sampler> &samplers,
                                        std::vector<Spectrum> *li_out = nullptr) {
    std::vector<Sampler> batch_samplers = samplers, ref_samplers = samplers;
    std::vector<Spectrum> batch(rays.size());
    RayCounters counters;
    integrator.li_batch(scene, rays.data(), batch_samplers.data(), batch.data(), rays.size(), counters);
    size_t nonzero = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        Spectrum ref = integrator.li(scene, rays[i], ref_samplers[i], counters);
        nonzero += !ref.is_black();
        if (li_out) li_out->push_back(ref);
        EXPECT_TRUE(same_bits(batch[i], ref)) << "path " << i << ": batch " << batch[i].r << " " << batch[i].g << " "
                                              << batch[i].b << ", li " << ref.r << " " << ref.g << " " << ref.b;
        if (::testing::Test::HasFailure()) break; // the first difference says enough
    }
    return nonzero;
}

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
