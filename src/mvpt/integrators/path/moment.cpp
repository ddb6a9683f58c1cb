// Mitsuba's `moment` integrator: a wrapper that records the second moment of its nested
// integrator's samples. mvpt always estimates the per-pixel variance of every view
// (RenderResult.variance), so `moment` loads as its single nested integrator; scenes of
// Mitsuba's test suite, which wrap `path` in `moment`, then load unchanged.
#include "../../render/integrator.h"
#include "../../core/plugin.h"

namespace mvpt {
namespace {

std::shared_ptr<Object> make_moment(const Properties &props, const LoadContext &) {
    auto nested = props.children_of_kind("integrator");
    if (nested.size() != 1)
        props.fail("integrator", "mvpt's moment integrator needs exactly one nested <integrator> (got " +
                                     std::to_string(nested.size()) + "); its variance is always estimated");
    return nested.front()->object;
}

} // namespace

MVPT_REGISTER_PLUGIN("integrator", "moment", make_moment);

} // namespace mvpt
