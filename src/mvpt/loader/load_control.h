// What the caller of a load asks of it besides the scene, for the thread that loads: a flag
// that stops it (Ctrl-C while a rig of many views is made), checked before each view a rig
// makes and each element instantiated, and whether every view will be rendered at once (then
// a rig whose views' images cannot fit in memory is refused before its views are made).
#pragma once

#include <atomic>
#include <stdexcept>

namespace mvpt {

struct LoadControl {
    const std::atomic<bool> *cancel = nullptr; ///< set by another thread: the load stops
    bool every_view_rendered = false;          ///< the caller renders all the views together
};

/// Thrown by a load whose cancel flag was set.
struct LoadCancelled : std::runtime_error {
    LoadCancelled() : std::runtime_error("the scene's load was cancelled") {}
};

/// Sets the control of this thread's loads while it lives.
class LoadControlScope {
public:
    explicit LoadControlScope(LoadControl control);
    ~LoadControlScope();
    LoadControlScope(const LoadControlScope &) = delete;
    LoadControlScope &operator=(const LoadControlScope &) = delete;

private:
    LoadControl m_previous;
};

/// This thread's load control (none set: never cancelled, nothing assumed of the render).
const LoadControl &load_control();

/// Throws LoadCancelled when this thread's load was asked to stop.
void check_load_cancelled();

} // namespace mvpt
