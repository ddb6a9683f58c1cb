#include "medium.h"

#include "../core/plugin.h"

namespace mvpt {

void Medium::read_common(const Properties &props) {
    if (const ChildObject *p = props.child_of_kind("phase")) m_phase = std::static_pointer_cast<PhaseFunction>(p->object);
    else m_phase = std::static_pointer_cast<PhaseFunction>(
             (*PluginRegistry::find("phase", "isotropic"))(Properties("phase", "isotropic", props.loc()), {}));
    m_sample_emitters = props.get_bool("sample_emitters", true);
    // Mitsuba's hint that sigma_t is grey (it then skips its per-channel weights); the channel
    // mixture here is exact either way, so the hint changes nothing.
    props.get_bool("has_spectral_extinction", true);
}

} // namespace mvpt
