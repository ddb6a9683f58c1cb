// Image texture (Mitsuba's `bitmap`): PNG/JPEG (sRGB-decoded unless `raw`),
// EXR and HDR; uv (0, 0) is the first pixel of the first (top) row, pixel
// centres at (i + 1/2) / width; bilinear or nearest lookup with repeat, mirror
// or clamp wrapping. The scalar value is the Rec. 709 luminance, as in Mitsuba.
#include "../../io/image_io.h"
#include "../../core/plugin.h"
#include "../texture.h"
#include "uv_transform.h"

#include <algorithm>
#include <cmath>

namespace mvpt {

class BitmapTexture final : public Texture {
public:
    enum class Wrap { Repeat, Mirror, Clamp };

    BitmapTexture(const Properties &props, const LoadContext &ctx) {
        std::string file = props.get_string("filename");
        auto path = ctx.resolve(file, props.loc_of("filename"));
        bool raw = props.get_bool("raw", false);
        std::string filter = props.get_string("filter_type", "bilinear");
        if (filter == "bilinear") m_bilinear = true;
        else if (filter == "nearest") m_bilinear = false;
        else props.fail("filter_type", "filter_type must be 'bilinear' or 'nearest', got '" + filter + "'");
        std::string wrap = props.get_string("wrap_mode", "repeat");
        if (wrap == "repeat") m_wrap = Wrap::Repeat;
        else if (wrap == "mirror") m_wrap = Wrap::Mirror;
        else if (wrap == "clamp") m_wrap = Wrap::Clamp;
        else props.fail("wrap_mode", "wrap_mode must be 'repeat', 'mirror' or 'clamp', got '" + wrap + "'");
        m_to_uv = UvTransform(props.get_transform("to_uv"));
        // Storage precision (Mitsuba's `format`): "variant" is float32 in scalar_rgb, as here.
        std::string format = props.get_string("format", "variant");
        if (format != "variant")
            props.fail("format", "format must be 'variant' (mvpt does not store textures as 'fp16'), got '" + format + "'");
        try {
            m_image = read_image(path, raw);
        } catch (const std::exception &e) {
            props.fail("filename", "cannot read image '" + file + "': " + e.what());
        }
        if (m_image.width <= 0 || m_image.height <= 0) props.fail("filename", "image '" + file + "' is empty");
        for (size_t i = 0; i < m_image.rgb.size(); i += 3) {
            Color3f c(m_image.rgb[i], m_image.rgb[i + 1], m_image.rgb[i + 2]);
            if (!c.is_finite()) props.fail("filename", "image '" + file + "' contains non-finite values");
            m_mean += c;
        }
        m_mean = m_mean / float(size_t(m_image.width) * m_image.height);
    }

    Color3f eval(Vec2f uv_in) const override {
        Vec2f uv = m_to_uv(uv_in);
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return {};
        const int w = m_image.width, h = m_image.height;
        if (!m_bilinear) return texel(to_int(std::floor(uv.x * float(w))), to_int(std::floor(uv.y * float(h))));
        const Cell c = cell(uv);
        return (texel(c.x0, c.y0) * (1.f - c.tx) + texel(c.x0 + 1, c.y0) * c.tx) * (1.f - c.ty) +
               (texel(c.x0, c.y0 + 1) * (1.f - c.tx) + texel(c.x0 + 1, c.y0 + 1) * c.tx) * c.ty;
    }

    float eval_1(Vec2f uv) const override { return eval(uv).luminance(); }
    /// The gradient of the bilinear interpolation of the luminance, by the chain rule through
    /// the uv transform (Mitsuba's eval_1_grad; zero for the nearest lookup).
    Vec2f eval_1_grad(Vec2f uv_in) const override {
        if (!m_bilinear) return {0.f, 0.f};
        Vec2f uv = m_to_uv(uv_in);
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return {0.f, 0.f};
        const Cell c = cell(uv);
        const float f00 = texel(c.x0, c.y0).luminance(), f10 = texel(c.x0 + 1, c.y0).luminance(),
                    f01 = texel(c.x0, c.y0 + 1).luminance(), f11 = texel(c.x0 + 1, c.y0 + 1).luminance();
        // d/dx and d/dy in pixels, then x = (a u + b v + c) w - 1/2, y = (d u + e v + f) h - 1/2.
        const float dx = (1.f - c.ty) * (f10 - f00) + c.ty * (f11 - f01),
                    dy = (1.f - c.tx) * (f01 - f00) + c.tx * (f11 - f10);
        const float w = float(m_image.width), h = float(m_image.height);
        return {m_to_uv.a * w * dx + m_to_uv.d * h * dy, m_to_uv.b * w * dx + m_to_uv.e * h * dy};
    }
    Color3f mean() const override { return m_mean; }

private:
    /// Bounded before the int conversion (far-out uvs only lose precision).
    static int to_int(float v) { return int(std::clamp(v, -1e9f, 1e9f)); }
    /// The bilinear lookup's texels at (transformed) uv: (x0, y0) to (x0 + 1, y0 + 1), and the
    /// weights tx, ty of the second column and row.
    struct Cell {
        int x0, y0;
        float tx, ty;
    };
    Cell cell(Vec2f uv) const {
        float x = uv.x * float(m_image.width) - 0.5f, y = uv.y * float(m_image.height) - 0.5f;
        float fx = std::floor(x), fy = std::floor(y);
        return {to_int(fx), to_int(fy), x - fx, y - fy};
    }
    int wrap(int i, int n) const {
        switch (m_wrap) {
            case Wrap::Clamp: return std::clamp(i, 0, n - 1);
            case Wrap::Repeat: return ((i % n) + n) % n;
            default: {
                int p = ((i % (2 * n)) + 2 * n) % (2 * n);
                return p < n ? p : 2 * n - 1 - p;
            }
        }
    }

    Color3f texel(int x, int y) const {
        const float *p = &m_image.rgb[3 * (size_t(wrap(y, m_image.height)) * m_image.width + wrap(x, m_image.width))];
        return {p[0], p[1], p[2]};
    }

    ImageRGB m_image;
    Color3f m_mean;
    UvTransform m_to_uv;
    bool m_bilinear = true;
    Wrap m_wrap = Wrap::Repeat;
};

MVPT_REGISTER_PLUGIN("texture", "bitmap", [](const Properties &p, const LoadContext &ctx) {
    return std::make_shared<BitmapTexture>(p, ctx);
});

} // namespace mvpt
