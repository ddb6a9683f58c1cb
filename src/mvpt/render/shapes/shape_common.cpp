#include "mesh.h"

#include "../bsdf.h"
#include "../light.h"

namespace mvpt {

void attach_shape_children(Shape &shape, const Properties &props) {
    shape.id = props.id;
    if (const ChildObject *b = props.child_of_kind("bsdf")) {
        shape.bsdf = std::static_pointer_cast<Bsdf>(b->object);
    } else {
        // Mitsuba's default material: diffuse with reflectance 0.5, black on emitters (its shape.cpp).
        Properties dp("bsdf", "diffuse", props.loc());
        for (auto &c : props.children())
            if (c.kind == "emitter") dp.set("reflectance", 0.0, props.loc(), "float");
        shape.bsdf = std::static_pointer_cast<Bsdf>((*PluginRegistry::find("bsdf", "diffuse"))(dp, {}));
    }
    if (const ChildObject *e = props.child_of_kind("emitter")) {
        auto light = std::static_pointer_cast<Light>(e->object);
        if (!light->is_area())
            throw SceneError(e->loc, "only an 'area' emitter can be attached to a shape, got '" + e->type + "'");
        if (light->shape())
            throw SceneError(e->loc, "an area emitter can be attached to one shape only");
        light->set_shape(&shape);
        shape.emitter = light;
    }
}

} // namespace mvpt
