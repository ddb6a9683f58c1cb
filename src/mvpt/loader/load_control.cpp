#include "load_control.h"

namespace mvpt {

namespace {
thread_local LoadControl t_control;
}

LoadControlScope::LoadControlScope(LoadControl control) : m_previous(t_control) { t_control = control; }

LoadControlScope::~LoadControlScope() { t_control = m_previous; }

const LoadControl &load_control() { return t_control; }

void check_load_cancelled() {
    if (t_control.cancel && t_control.cancel->load(std::memory_order_relaxed)) throw LoadCancelled();
}

} // namespace mvpt
