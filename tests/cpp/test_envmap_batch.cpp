// The environment map's batched entry points (Light::sample_li_batch, eval_environment_batch),
// which the wavefront path tracer calls for all lanes of a bounce at once, against the
// one-lane calls bit for bit: sample_li, eval_environment_pdf, eval_environment, pdf_li.
// Also li_batch against li on the envmap feature scene (test_path_batch.cpp skips it, as
// its EXR is written by a test).
#include "batch_checks.h"
#include "mvpt/core/sampler.h"
#include "mvpt/core/warp.h"
#include "mvpt/integrators/path/path.h"
#include "mvpt/io/image_io.h"
#include "mvpt/render/light.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

using namespace mvpt;

namespace {

using test::same_bits;

bool same_sample(const LightSample &a, const LightSample &b) {
    return same_bits(a.p, b.p) && same_bits(a.n, b.n) && same_bits(a.d, b.d) && same_bits(a.dist, b.dist) &&
           same_bits(a.pdf, b.pdf) && a.delta == b.delta;
}

/// A temporary directory, removed with its contents when this goes out of scope.
struct TempDir {
    std::filesystem::path path;
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
};

/// A small random lat-long map (`w` x `h`) with black texels and a black row (zero-density
/// patches and rows the samplers must skip), written as env.exr to a fresh temporary directory.
TempDir write_envmap(int w, int h) {
    TempDir dir{std::filesystem::temp_directory_path() / ("mvpt_envmap_batch_" + std::to_string(::getpid()))};
    std::filesystem::create_directories(dir.path);
    std::vector<ExrChannel> ch = {{"R", {}}, {"G", {}}, {"B", {}}};
    Sampler s(SamplerKind::Independent, 11);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            s.start(0, uint32_t(x), uint32_t(y), 0);
            const bool black = y == 2 || (x + y) % 7 == 0;
            const float bright = (x == 3 && y == 1) ? 40.f : 1.f; // a "sun"
            for (auto &c : ch) c.data.push_back(black ? 0.f : bright * s.next_1d());
        }
    write_exr(dir.path / "env.exr", w, h, ch);
    return dir;
}

/// The minimal sensor a loadable scene needs.
constexpr const char *Sensor = R"(<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/>
        <integer name="height" value="4"/></film></sensor>)";

std::unique_ptr<Scene> envmap_scene(const std::filesystem::path &dir, bool mis_compensation) {
    const std::string xml = R"(<scene version="3.0.0">
        <emitter type="envmap">
            <string name="filename" value="env.exr"/>
            <float name="scale" value="1.5"/>
            <boolean name="mis_compensation" value=")" + std::string(mis_compensation ? "true" : "false") + R"("/>
            <transform name="to_world"><rotate x="0.3" y="1" angle="30"/></transform>
        </emitter>
        <shape type="sphere"><float name="radius" value="0.5"/></shape>)" + std::string(Sensor) + "</scene>";
    return load_scene_string(xml, dir);
}

constexpr float OneMinusUlp = 0x1.fffffep-1f;

} // namespace

TEST(EnvmapBatch, SampleLiBatchEqualsSampleLi) {
    const auto dir = write_envmap(37, 19);
    for (bool mis : {false, true}) {
        SCOPED_TRACE(mis ? "mis_compensation" : "plain");
        auto scene = envmap_scene(dir.path, mis);
        const Light *env = scene->environment();
        ASSERT_NE(env, nullptr);
        // Random reference points and numbers, then the edges of [0, 1)^2; more lanes than one stage holds.
        std::vector<Point3f> ref;
        std::vector<Vec2f> u;
        Sampler s(SamplerKind::Independent, 5);
        for (uint32_t i = 0; i < 300; ++i) {
            s.start(0, i, 0, 0);
            ref.push_back(Point3f(4.f * s.next_1d() - 2.f, 4.f * s.next_1d() - 2.f, 4.f * s.next_1d() - 2.f));
            u.push_back(s.next_2d());
        }
        const float edges[] = {0.f, 0x1p-30f, 0.5f, OneMinusUlp};
        for (float a : edges)
            for (float b : edges) {
                ref.push_back(Point3f(0.1f, -0.3f, 0.7f));
                u.push_back({a, b});
            }
        const std::vector<float> time(u.size(), 0.5f);
        // Whole, a single lane and nothing (n = 0 writes nothing).
        for (size_t n : {u.size(), size_t(1), size_t(0)}) {
            std::vector<LightSample> ls(n + 1);
            std::vector<Spectrum> weight(n + 1, Spectrum(-1.f));
            env->sample_li_batch(n, ref.data(), u.data(), time.data(), ls.data(), weight.data());
            size_t nonzero = 0;
            for (size_t i = 0; i < n; ++i) {
                auto [ref_ls, ref_weight] = env->sample_li(ref[i], u[i], time[i]);
                nonzero += !ref_weight.is_black();
                ASSERT_TRUE(same_sample(ls[i], ref_ls)) << "lane " << i << " u " << u[i].x << " " << u[i].y;
                ASSERT_TRUE(same_bits(weight[i], ref_weight)) << "lane " << i << " u " << u[i].x << " " << u[i].y;
            }
            EXPECT_TRUE(same_bits(weight[n], Spectrum(-1.f))); // nothing past the last lane
            if (n > 1) EXPECT_GT(nonzero, n / 2);               // the comparison saw samples
        }
    }
}

TEST(EnvmapBatch, EvalEnvironmentBatchEqualsScalar) {
    const auto dir = write_envmap(37, 19);
    for (bool mis : {false, true}) {
        SCOPED_TRACE(mis ? "mis_compensation" : "plain");
        auto scene = envmap_scene(dir.path, mis);
        const Light *env = scene->environment();
        ASSERT_NE(env, nullptr);
        // Random directions, then the poles, the seam of the lat-long map and nearly vertical ones.
        std::vector<Vec3f> d;
        Sampler s(SamplerKind::Independent, 6);
        for (uint32_t i = 0; i < 300; ++i) {
            s.start(0, i, 0, 0);
            d.push_back(warp::square_to_uniform_sphere(s.next_2d()));
        }
        for (Vec3f v : {Vec3f(0.f, 1.f, 0.f), Vec3f(0.f, -1.f, 0.f), Vec3f(0.f, 0.f, 1.f), Vec3f(0.f, 0.f, -1.f),
                        Vec3f(-0x1p-30f, 0.f, -1.f), Vec3f(0x1p-30f, 0.f, -1.f), Vec3f(0x1p-13f, 1.f, 0.f)})
            d.push_back(normalize(v));
        std::vector<Point3f> ref(d.size(), Point3f(0.2f, 0.1f, -0.4f));
        const SurfaceInteraction si_none;
        std::vector<Spectrum> le(d.size()), le_only(d.size());
        std::vector<float> pdf(d.size(), -1.f);
        env->eval_environment_batch(d.size(), ref.data(), d.data(), le.data(), pdf.data());
        env->eval_environment_batch(d.size(), ref.data(), d.data(), le_only.data(), nullptr);
        size_t nonzero = 0;
        for (size_t i = 0; i < d.size(); ++i) {
            float ref_pdf = -2.f;
            Spectrum ref_le = env->eval_environment_pdf(ref[i], si_none, d[i], &ref_pdf);
            nonzero += ref_pdf > 0.f;
            ASSERT_TRUE(same_bits(le[i], ref_le)) << "lane " << i;
            ASSERT_TRUE(same_bits(pdf[i], ref_pdf)) << "lane " << i << ": " << pdf[i] << " vs " << ref_pdf;
            ASSERT_TRUE(same_bits(pdf[i], env->pdf_li(ref[i], si_none, d[i]))) << "lane " << i;
            ASSERT_TRUE(same_bits(le_only[i], env->eval_environment(d[i]))) << "lane " << i;
        }
        EXPECT_GT(nonzero, d.size() / 2);
    }
}

// Light's default batch entry points loop over the one-lane calls (here a constant environment).
TEST(EnvmapBatch, DefaultBatchLoopsOverLanes) {
    auto scene = load_scene_string(R"(<scene version="3.0.0">
        <emitter type="constant"><rgb name="radiance" value="0.5, 1, 2"/></emitter>
        <shape type="sphere"/>)" + std::string(Sensor) + "</scene>", std::filesystem::temp_directory_path());
    const Light *env = scene->environment();
    ASSERT_NE(env, nullptr);
    std::vector<Point3f> ref = {Point3f(0.f, 0.f, 2.f), Point3f(1.f, 2.f, 3.f)};
    std::vector<Vec2f> u = {{0.f, 0.f}, {0.3f, OneMinusUlp}};
    std::vector<float> time = {0.f, 1.f};
    std::vector<LightSample> ls(2);
    std::vector<Spectrum> weight(2), le(2);
    std::vector<float> pdf(2);
    env->sample_li_batch(2, ref.data(), u.data(), time.data(), ls.data(), weight.data());
    std::vector<Vec3f> d = {ls[0].d, ls[1].d};
    env->eval_environment_batch(2, ref.data(), d.data(), le.data(), pdf.data());
    const SurfaceInteraction si_none;
    for (size_t i = 0; i < 2; ++i) {
        auto [ref_ls, ref_weight] = env->sample_li(ref[i], u[i], time[i]);
        EXPECT_TRUE(same_sample(ls[i], ref_ls));
        EXPECT_TRUE(same_bits(weight[i], ref_weight));
        float ref_pdf;
        EXPECT_TRUE(same_bits(le[i], env->eval_environment_pdf(ref[i], si_none, d[i], &ref_pdf)));
        EXPECT_TRUE(same_bits(pdf[i], ref_pdf));
    }
}

// The wavefront with the envmap as the scene's environment: escaped rays and emitter samples
// go through the batched calls; each path's radiance stays li's bit for bit.
TEST(EnvmapBatch, PathBatchWithEnvmapBitIdenticalToLi) {
    const auto dir = write_envmap(37, 19);
    const auto scene_file =
        std::filesystem::path(__FILE__).parent_path().parent_path() / "scenes" / "features" / "emitter_envmap.xml";
    auto scene = load_scene_file(scene_file, {{"envmap_file", (dir.path / "env.exr").string()}});
    ASSERT_NE(scene->environment(), nullptr);
    for (int variant = 0; variant < 3; ++variant) {
        // The scene's integrator, then hidden emitters, then long paths with Russian roulette.
        PathConfig cfg;
        if (auto *p = dynamic_cast<const PathIntegrator *>(&scene->integrator())) cfg = p->config();
        if (variant == 1) { cfg.max_depth = 3; cfg.hide_emitters = true; }
        if (variant == 2) { cfg.max_depth = -1; cfg.rr_depth = 2; }
        PathIntegrator integrator(cfg);
        std::vector<Ray> rays;
        std::vector<Sampler> samplers;
        test::camera_rays(*scene, 16, 2, rays, samplers);
        SCOPED_TRACE("variant " + std::to_string(variant));
        const size_t nonzero = test::expect_li_batch_equals_li(*scene, integrator, rays, samplers);
        if (HasFailure()) return;
        EXPECT_GT(nonzero, rays.size() / 2) << "variant " << variant;
    }
}

// trace_batch (multi-view suffixes) from given states on the envmap scene, against trace:
// states with delta and smooth previous lobes, so escaped rays take both batched evaluations.
TEST(EnvmapBatch, TraceBatchWithEnvmapContinuesLikeTrace) {
    const auto dir = write_envmap(37, 19);
    const auto scene_file =
        std::filesystem::path(__FILE__).parent_path().parent_path() / "scenes" / "features" / "emitter_envmap.xml";
    auto scene = load_scene_file(scene_file, {{"envmap_file", (dir.path / "env.exr").string()}});
    PathConfig cfg;
    if (auto *p = dynamic_cast<const PathIntegrator *>(&scene->integrator())) cfg = p->config();
    cfg.rr_depth = 2;
    PathIntegrator integrator(cfg);
    const Camera &cam = *scene->cameras()[0];
    std::vector<Ray> rays;
    std::vector<Sampler> samplers;
    std::vector<PathState> states;
    const int res = 24;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            Sampler s(cam.sampler_kind, 9);
            s.start(0, uint32_t(x), uint32_t(y), 0);
            s.set_dimension(DimFilm);
            Vec2f u_film = s.next_2d();
            Ray camera_ray = cam.generate_ray(
                Vec2f((x + u_film.x) * cam.film.width / res, (y + u_film.y) * cam.film.height / res), Vec2f(0.f, 0.f), 0.f);
            SurfaceInteraction si;
            if (!scene->intersect(camera_ray, si)) continue;
            PathState st;
            st.depth = 1 + uint32_t(s.next_1d() * 3.f);
            st.throughput = Spectrum(0.2f + s.next_1d(), 0.5f, 0.2f + s.next_1d());
            st.prev_p = si.p;
            st.prev_bsdf_pdf = 0.05f + 2.f * s.next_1d();
            st.prev_bsdf_delta = s.next_1d() < 0.3f;
            st.valid = s.next_1d() < 0.7f;
            Vec3f d = warp::square_to_uniform_sphere(s.next_2d());
            if (dot(d, si.n) * dot(camera_ray.d, si.n) > 0.f) d = -d; // back to the camera's side, as a bounce
            rays.push_back(si.spawn_ray(d));
            states.push_back(st);
            samplers.push_back(s);
        }
    ASSERT_GT(rays.size(), 100u);
    const size_t nonzero = test::expect_trace_batch_equals_trace(*scene, integrator, rays, states, samplers);
    EXPECT_GT(nonzero, rays.size() / 2);
}
