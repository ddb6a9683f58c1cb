// `constvolume`: one value everywhere; also what a medium's constant parameters become.
#include "../../core/plugin.h"
#include "../volume.h"

#include <cstdio>

namespace mvpt {

namespace {

class ConstVolume final : public Volume {
public:
    explicit ConstVolume(Spectrum v) : m_value(v) {}
    Spectrum eval(Point3f) const override { return m_value; }
    float max_value() const override { return m_value.max_value(); }
    float min_value() const override { return m_value.min_value(); }
    BoundingBox bounds() const override {
        return {Point3f(-Infinity, -Infinity, -Infinity), Point3f(Infinity, Infinity, Infinity)};
    }
    int channels() const override { return 3; }
    bool constant(Spectrum &value) const override { value = m_value; return true; }

private:
    Spectrum m_value;
};

} // namespace

std::shared_ptr<Volume> constant_volume(Spectrum value) { return std::make_shared<ConstVolume>(value); }

std::shared_ptr<Volume> get_volume(const Properties &props, const std::string &name, Color3f def, SpectrumUse use) {
    for (const ChildObject &c : props.children())
        if (c.kind == "volume" && c.name == name) {
            c.queried = true;
            return std::static_pointer_cast<Volume>(c.object);
        }
    return constant_volume(props.get_color(name, def, use));
}

namespace {
std::string shortest(float v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", double(v));
    return buf;
}
} // namespace

void check_volume_range(const Properties &props, const std::string &name, const Volume &v, float lo, float hi,
                        const char *what) {
    if (!(v.min_value() >= lo) || !(v.max_value() <= hi))
        props.fail(name, name + " must lie in [" + shortest(lo) + ", " + shortest(hi) + "] (" + what +
                             "), got values from " + shortest(v.min_value()) + " to " + shortest(v.max_value()));
}

MVPT_REGISTER_PLUGIN("volume", "constvolume", [](const Properties &p, const LoadContext &) {
    return std::make_shared<ConstVolume>(p.get_color("value", Color3f(0.75f), SpectrumUse::Unbounded));
});

} // namespace mvpt
