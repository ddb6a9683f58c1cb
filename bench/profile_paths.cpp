// Renders a prepared scene with one thread, for callgrind: instructions per camera path.
//
//   python bench/profile_paths.py cbox-rgb --res 32 --write-xml /tmp/cbox.xml   # prints the base dir
//   valgrind --tool=callgrind build/prof/mvpt_profile /tmp/cbox.xml BASE_DIR 64
//
// Prints the camera path count and an FNV-1a hash of the float image (bit-identity checks).
// It renders the scene's first view; with MVPT_PROFILE_ALL_VIEWS=1 in the environment it renders
// every view (a multi-view scene whose integrator is mvpath), still hashing the first view's image.
#include "mvpt/loader/load_scene.h"
#include "mvpt/renderer/renderer.h"

#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <fstream>
#include <sstream>

int main(int argc, char **argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: %s scene.xml base_dir spp [threads]\n", argv[0]);
        return 2;
    }
    std::ifstream in(argv[1]);
    std::stringstream xml;
    xml << in.rdbuf();
    auto scene = mvpt::load_scene_string(xml.str(), argv[2]);
    mvpt::RenderOptions opts;
    opts.spp = std::atoi(argv[3]);
    opts.threads = argc > 4 ? std::atoi(argv[4]) : 1;
    opts.seed = 1;
    if (!std::getenv("MVPT_PROFILE_ALL_VIEWS")) opts.views = {0}; // one view, unless told
    mvpt::Renderer renderer(*scene, opts);
    std::atomic<bool> cancel{false};
    auto cpu = [] { timespec ts; clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts); return ts.tv_sec + 1e-9 * ts.tv_nsec; };
    double c0 = cpu();
    auto t0 = std::chrono::steady_clock::now();
    renderer.render(cancel);
    double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double dc = cpu() - c0;
    const mvpt::ViewResult &r = renderer.results()[0];
    uint64_t h = 1469598103934665603ULL;
    for (float f : r.rgb) {
        uint32_t bits;
        std::memcpy(&bits, &f, 4);
        for (int i = 0; i < 4; ++i) h = (h ^ ((bits >> (8 * i)) & 0xffu)) * 1099511628211ULL;
    }
    double paths = double(r.width) * r.height * opts.spp;
    const mvpt::RayCounters &c = renderer.stats().counters;
    std::printf("%dx%d x %d spp = %.0f camera paths, %.3f s (%.3f s CPU), %.3f M paths/s per CPU second, %d thread(s), "
                "%.3f rays and %.3f shadow rays per path, image hash %016llx\n",
                r.width, r.height, opts.spp, paths, dt, dc, paths / dc * 1e-6, opts.threads, double(c.rays) / paths,
                double(c.shadow_rays) / paths, (unsigned long long)h);
    return 0;
}
