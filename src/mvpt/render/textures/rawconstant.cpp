// Raw constant (Mitsuba's `rawconstant`): a <float> or <vector> `value` returned as it is, with
// no colour conversion or clamping (data such as a constant normal map).
#include "../../core/plugin.h"
#include "../texture.h"

namespace mvpt {

MVPT_REGISTER_PLUGIN("texture", "rawconstant", [](const Properties &p, const LoadContext &) {
    if (!p.has("value")) p.fail("value", "rawconstant needs a <float> or <vector> 'value'");
    const Vec3f v = p.is_vector("value") ? p.get_vector("value", {}) : Vec3f(p.get_float("value"));
    return std::make_shared<ConstantTexture>(Color3f(v.x, v.y, v.z));
});

} // namespace mvpt
