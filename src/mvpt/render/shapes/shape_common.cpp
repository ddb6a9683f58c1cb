#include "mesh.h"

#include "../bsdf.h"
#include "../light.h"
#include "../medium.h"

namespace mvpt {

void attach_shape_children(Shape &shape, const Properties &props) {
    shape.id = props.id;
    const ChildObject *e = props.child_of_kind("emitter");
    if (const ChildObject *b = props.child_of_kind("bsdf")) {
        shape.bsdf = std::static_pointer_cast<Bsdf>(b->object);
    } else {
        // Mitsuba's default material: diffuse with reflectance 0.5, or 0 (black) on an emitter.
        Properties dp("bsdf", "diffuse", props.loc());
        if (e) dp.set("reflectance", Properties::Value(Color3f(0.f)), props.loc(), "rgb");
        shape.bsdf = std::static_pointer_cast<Bsdf>((*PluginRegistry::find("bsdf", "diffuse"))(dp, {}));
    }
    for (const ChildObject *m : props.children_of_kind("medium")) {
        auto medium = std::static_pointer_cast<Medium>(m->object);
        if (m->name == "interior") shape.interior = medium;
        else if (m->name == "exterior") shape.exterior = medium;
        else throw SceneError(m->loc, "a shape's medium must be named 'interior' or 'exterior', got '" + m->name + "'");
    }
    if (e) {
        auto light = std::static_pointer_cast<Light>(e->object);
        if (!light->is_area())
            throw SceneError(e->loc, "only an 'area' emitter can be attached to a shape, got '" + e->type + "'");
        if (light->shape())
            throw SceneError(e->loc, "an area emitter can be attached to one shape only");
        light->set_shape(&shape);
        shape.emitter = light;
        shape.sample_uv = !light->uniform_radiance();
    }
}

} // namespace mvpt
