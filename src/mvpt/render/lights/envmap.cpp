// Environment map emitter (Mitsuba's `envmap`): a latitude-longitude image at
// infinity, looked up bilinearly and importance sampled with a piecewise-
// bilinear density proportional to luminance x sin(theta).
//
// Mapping (Mitsuba 3, emitters/envmap.cpp), in emitter space:
//   u = atan2(d.x, -d.z) / 2pi, v = acos(d.y) / pi,
//   d = (sin(phi) sin(theta), cos(theta), -cos(phi) sin(theta)), phi = 2pi u, theta = pi v.
// Pixel column x sits at u = (x + 1/2) / W (periodic in u); pixel row y sits at
// v = y / (H - 1), so the first and last rows are the poles.
#include "../../core/bilinear_distribution.h"
#include "../../core/poly_math.h"
#include "../../core/warp.h"
#include "../../io/image_io.h"
#include "../../core/plugin.h"
#include "../light.h"

#include <cmath>

namespace mvpt {

class EnvironmentMap final : public Light {
public:
    EnvironmentMap(const Properties &props, const LoadContext &ctx) {
        std::string filename = props.get_string("filename");
        auto path = ctx.resolve(filename, props.loc_of("filename"));
        ImageRGB img;
        try {
            img = read_image(path);
        } catch (const std::exception &e) {
            props.fail("filename", "cannot load environment map '" + filename + "': " + e.what());
        }
        if (img.width < 2 || img.height < 3)
            props.fail("filename", "'" + filename + "': the environment map resolution must be at least 2x3 pixels");
        for (float v : img.rgb)
            if (!std::isfinite(v)) props.fail("filename", "'" + filename + "' contains non-finite pixel values");
        m_scale = props.get_float("scale", 1.f);
        if (!std::isfinite(m_scale)) props.fail("scale", "'scale' must be finite");
        m_to_world = props.get_transform("to_world");
        m_to_local = m_to_world.inverse();
        bool mis_compensation = props.get_bool("mis_compensation", false);
        m_flags = LightInfinite;

        // One extra column repeats the first, making the lookup periodic in u.
        m_w = img.width + 1;
        m_h = img.height;
        m_texels.resize(size_t(m_w) * m_h);
        for (int y = 0; y < m_h; ++y)
            for (int x = 0; x < m_w; ++x) {
                const float *p = &img.rgb[3 * (size_t(y) * img.width + size_t(x % img.width))];
                m_texels[size_t(y) * m_w + x] = Color3f(p[0], p[1], p[2]);
            }
        build_distribution(mis_compensation);
    }

    void set_scene_bounds(Point3f center, float radius) override {
        m_center = center;
        m_radius = radius;
    }

    std::pair<LightSample, Spectrum> sample_li(Point3f ref, Vec2f u, float) const override {
        float pdf_uv;
        // The texels that `lookup` reads below are those of the sampled patch: fetching
        // them while the sampler reads the patch's density overlaps two cache misses.
        Vec2f uv = m_distr.sample(u, &pdf_uv, [this](int x, int y) { prefetch_texels(x, y); });
        std::pair<LightSample, Spectrum> out;
        sample_from_uv(ref, uv, pdf_uv, out.first, out.second);
        return out;
    }

    /// sample_li's lanes in stages (BilinearDistribution2D::sample_batch, then the directions
    /// and texels of all lanes), so that different lanes' table and texel reads overlap.
    void sample_li_batch(size_t n, const Point3f *ref, const Vec2f *u, const float *, LightSample *ls,
                         Spectrum *weight) const override {
        constexpr size_t Chunk = BilinearDistribution2D::BatchChunk;
        Vec2f uv[Chunk];
        float pdf_uv[Chunk];
        for (size_t i0 = 0; i0 < n; i0 += Chunk) {
            const size_t m = std::min(Chunk, n - i0);
            m_distr.sample_batch(m, u + i0, uv, pdf_uv, [this](size_t, int x, int y) { prefetch_texels(x, y); });
            for (size_t i = 0; i < m; ++i) sample_from_uv(ref[i0 + i], uv[i], pdf_uv[i], ls[i0 + i], weight[i0 + i]);
        }
    }

    float pdf_li(Point3f, const SurfaceInteraction &, Vec3f d) const override {
        Vec3f v = m_to_local.vector(d);
        return pdf_local(v, direction_to_uv(v));
    }

    Spectrum eval_environment(Vec3f d) const override {
        return lookup(direction_to_uv(m_to_local.vector(d)));
    }

    Spectrum eval_environment_pdf(Point3f, const SurfaceInteraction &, Vec3f d, float *pdf) const override {
        Vec3f v = m_to_local.vector(d);
        Vec2f uv = direction_to_uv(v);
        if (pdf) *pdf = pdf_local(v, uv);
        return lookup(uv);
    }

    /// eval_environment_pdf's lanes in two stages: all directions' lat-long coordinates, then
    /// all densities and texels (independent reads that overlap).
    void eval_environment_batch(size_t n, const Point3f *, const Vec3f *d, Spectrum *le, float *pdf) const override {
        constexpr size_t Chunk = BilinearDistribution2D::BatchChunk;
        Vec3f v[Chunk];
        Vec2f uv[Chunk];
        for (size_t i0 = 0; i0 < n; i0 += Chunk) {
            const size_t m = std::min(Chunk, n - i0);
            for (size_t i = 0; i < m; ++i) {
                v[i] = m_to_local.vector(d[i0 + i]);
                uv[i] = direction_to_uv(v[i]);
            }
            for (size_t i = 0; i < m; ++i) prefetch_lookup(uv[i]);
            if (pdf)
                for (size_t i = 0; i < m; ++i) pdf[i0 + i] = pdf_local(v[i], uv[i]);
            for (size_t i = 0; i < m; ++i) le[i0 + i] = lookup(uv[i]);
        }
    }

private:
    /// Mitsuba's dr::Epsilon<float> (2^-24), the floor on sin(theta).
    static constexpr float Epsilon = 0x1p-24f;

    float half_texel() const { return 0.5f / float(m_w - 1); }

    /// Fetch the texels that `lookup` reads for a point in patch (x, y) (texels x and x + 1 of
    /// rows y and y + 1: 24 bytes each, possibly across a line boundary).
    void prefetch_texels(int x, int y) const {
        const Color3f *row0 = &m_texels[size_t(y) * m_w + x], *row1 = row0 + m_w;
        __builtin_prefetch(row0);
        __builtin_prefetch(row1);
        __builtin_prefetch(reinterpret_cast<const char *>(row0 + 2) - 1);
        __builtin_prefetch(reinterpret_cast<const char *>(row1 + 2) - 1);
    }

    /// Fetch the texels and density vertices that lookup(uv) and pdf_local(v, uv) read.
    void prefetch_lookup(Vec2f uv) const {
        uv.x -= half_texel();
        uv = {uv.x - std::floor(uv.x), uv.y - std::floor(uv.y)};
        float fx = uv.x * float(m_w - 1), fy = uv.y * float(m_h - 1);
        int x = std::min(int(fx), m_w - 2), y = std::min(int(fy), m_h - 2);
        prefetch_texels(x, y);
        m_distr.prefetch_cell(x, y);
    }

    /// The rest of sample_li from the sampled lat-long point `uv` and its density `pdf_uv`.
    void sample_from_uv(Point3f ref, Vec2f uv, float pdf_uv, LightSample &ls, Spectrum &weight) const {
        ls = LightSample();
        if (!(pdf_uv > 0.f)) {
            weight = Spectrum();
            return;
        }
        uv.x += half_texel();
        float inv_sin_theta;
        Vec3f d = m_to_world.vector(uv_to_direction(uv, inv_sin_theta));
        ls.d = d;
        ls.n = -d;
        ls.dist = 2.f * std::max(m_radius, norm(ref - m_center));
        ls.p = ref + d * ls.dist;
        // Jacobian of the lat-long map: dA_uv = dw / (2 pi^2 sin(theta)).
        ls.pdf = pdf_uv * inv_sin_theta * (1.f / (2.f * Pi * Pi));
        weight = lookup(uv) / ls.pdf;
    }

    /// pdf_li of the emitter-space direction `v`, whose lat-long coordinates are `uv`.
    float pdf_local(Vec3f v, Vec2f uv) const {
        uv.x -= half_texel();
        uv = {uv.x - std::floor(uv.x), uv.y - std::floor(uv.y)};
        float inv_sin_theta = 1.f / std::sqrt(std::max(v.x * v.x + v.z * v.z, sqr(Epsilon)));
        return m_distr.pdf(uv) * inv_sin_theta * (1.f / (2.f * Pi * Pi));
    }

    /// The trigonometry of both maps is libm-free and branch-free (warp::sincos_turn,
    /// atan2_poly: within 4e-7 of libm), so that the batch loops vectorise.
    static Vec3f uv_to_direction(Vec2f uv, float &inv_sin_theta) {
        // theta = pi v is half a turn of v, phi = 2 pi u a whole turn of u.
        const Vec2f theta = warp::sincos_turn(0.5f * uv.y), phi = warp::sincos_turn(uv.x);
        const float sin_theta = theta.x, cos_theta = theta.y;
        inv_sin_theta = 1.f / std::max(sin_theta, Epsilon);
        return {phi.x * sin_theta, cos_theta, -phi.y * sin_theta};
    }

    /// theta = acos(d.y) as atan2(|d.xz|, d.y): the same angle for a unit d, and accurate near the poles.
    static Vec2f direction_to_uv(Vec3f d) {
        return {atan2_poly(d.x, -d.z) * InvTwoPi, atan2_poly(std::sqrt(d.x * d.x + d.z * d.z), d.y) * InvPi};
    }

    /// Bilinear texel lookup at lat-long coordinates `uv` (wrapped as Mitsuba does).
    Spectrum lookup(Vec2f uv) const {
        uv.x -= half_texel();
        uv = {uv.x - std::floor(uv.x), uv.y - std::floor(uv.y)};
        float fx = uv.x * float(m_w - 1), fy = uv.y * float(m_h - 1);
        int x = std::min(int(fx), m_w - 2), y = std::min(int(fy), m_h - 2);
        float wx = fx - float(x), wy = fy - float(y);
        const Color3f *row0 = &m_texels[size_t(y) * m_w], *row1 = row0 + m_w;
        Color3f v0 = row0[x] * (1.f - wx) + row0[x + 1] * wx;
        Color3f v1 = row1[x] * (1.f - wx) + row1[x + 1] * wx;
        return (v0 * (1.f - wy) + v1 * wy) * m_scale;
    }

    /// Luminance x sin(theta) at the vertices, optionally minus the mean
    /// luminance ["MIS compensation", Karlik et al. 2019].
    void build_distribution(bool mis_compensation) {
        std::vector<float> lum(m_texels.size());
        for (size_t i = 0; i < lum.size(); ++i) lum[i] = m_texels[i].luminance();
        float offset = 0.f;
        if (mis_compensation) {
            double sum = 0;
            float min_lum = Infinity;
            for (int y = 0; y < m_h; ++y)
                for (int x = 0; x < m_w - 1; ++x) {
                    float l = lum[size_t(y) * m_w + x];
                    sum += l;
                    min_lum = std::min(min_lum, l);
                }
            offset = float(sum / (double(m_w - 1) * m_h));
            if (offset - min_lum <= 0.01f * offset) offset = 0.f; // nearly constant map: disable
        }
        float theta_scale = Pi / float(m_h - 1);
        for (int y = 0; y < m_h; ++y) {
            // sin(pi) rounds to a tiny negative float: clamp so the density stays >= 0.
            float sin_theta = std::max(std::sin(float(y) * theta_scale), 0.f);
            for (int x = 0; x < m_w; ++x) {
                float &l = lum[size_t(y) * m_w + x];
                l = std::max(l - offset, 0.f) * sin_theta;
            }
        }
        m_distr = BilinearDistribution2D(lum, m_w, m_h);
    }

    int m_w = 0, m_h = 0;
    std::vector<Color3f> m_texels;
    float m_scale = 1.f;
    Transform m_to_world, m_to_local;
    BilinearDistribution2D m_distr;
    Point3f m_center{0.f};
    float m_radius = 1.f;
};

MVPT_REGISTER_PLUGIN("emitter", "envmap", [](const Properties &p, const LoadContext &ctx) {
    return std::make_shared<EnvironmentMap>(p, ctx);
});

} // namespace mvpt
