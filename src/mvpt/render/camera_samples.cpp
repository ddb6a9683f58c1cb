#include "camera_samples.h"

#include "../core/sampler.h"
#include "../core/sampler_batch.h"
#include "../core/warp.h"
#include "camera.h"
#include "filter.h"
#include "integrator.h"

namespace mvpt {

void CameraSamples::draw(const Camera &cam, uint32_t seed, uint32_t view, const uint32_t *px, const uint32_t *py,
                         const uint32_t *index, size_t n, FilmSampling film_sampling, bool lens_always) {
    static_assert(DimFilm == 0 && DimLens == 1 && DimTime == 2 && DimCameraEnd == 3,
                  "independent_start_draws draws the camera dimensions 0, 1, 2");
    film.resize(n), lens.resize(n), time.resize(n), weight.resize(n);
    const bool independent = cam.sampler_kind == SamplerKind::Independent;
    if (independent) { // the samplers' starts and camera numbers in one vector loop (sampler_batch.h)
        pixel_hash.resize(n), sample_hash.resize(n);
        for (auto &d : draws) d.resize(n);
        float *const out[5] = {draws[0].data(), draws[1].data(), draws[2].data(), draws[3].data(), draws[4].data()};
        independent_start_draws(seed, view, px, py, index, n, pixel_hash.data(), sample_hash.data(), out);
    } else {
        pixel_hash.clear(), sample_hash.clear();
    }
    const bool with_lens = lens_always || cam.lens_radius() > 0.f; // per batch, not per sample (a virtual call)
    const ReconstructionFilter &filter = *cam.film.filter;
    for (size_t i = 0; i < n; ++i) {
        Vec2f u_film, u_lens;
        float u_time;
        if (independent) {
            u_film = {draws[0][i], draws[1][i]};
            u_lens = {draws[2][i], draws[3][i]};
            u_time = draws[4][i];
        } else {
            Sampler sampler(cam.sampler_kind, seed);
            sampler.start(view, px[i], py[i], index[i], DimFilm);
            u_film = sampler.next_2d();
            u_lens = sampler.next_2d();
            u_time = sampler.next_1d();
        }
        const Vec2f pixel{float(int32_t(px[i])), float(int32_t(py[i]))};
        if (film_sampling == FilmSampling::Filter) {
            const Vec2f offset = filter.sample(u_film, weight[i]);
            film[i] = Vec2f(pixel.x + 0.5f + offset.x, pixel.y + 0.5f + offset.y);
        } else {
            film[i] = Vec2f(pixel.x + u_film.x, pixel.y + u_film.y);
            weight[i] = 1.f;
        }
        lens[i] = with_lens ? warp::square_to_uniform_disk_concentric(u_lens) : Vec2f(0.f, 0.f);
        time[i] = cam.sample_time(u_time);
    }
}

void CameraSamples::start(Sampler &sampler, size_t i, uint32_t view, uint32_t px, uint32_t py, uint32_t index,
                          uint32_t dim) const {
    if (!pixel_hash.empty()) sampler.start_from(pixel_hash[i], sample_hash[i], index, dim);
    else sampler.start(view, px, py, index, dim);
}

} // namespace mvpt
