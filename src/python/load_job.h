// A scene's load on a thread of its own, which Python waits for with the GIL released: a
// signal handler (Ctrl-C) then runs between the waits and cancels the load within a fraction
// of a second, where a load of 10^5 rig views holding the GIL answered only once done.
#pragma once

#include "mvpt/loader/load_control.h"
#include "mvpt/loader/load_scene.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace mvpt_py {

class LoadJob {
public:
    using Load = std::function<std::unique_ptr<mvpt::Scene>()>;

    /// `every_view_rendered`: the caller renders all the views at once (LoadControl).
    LoadJob(Load load, bool every_view_rendered) : m_load(std::move(load)), m_every_view(every_view_rendered) {}
    ~LoadJob() {
        m_cancel = true;
        if (m_thread.joinable()) m_thread.join();
    }

    void start() {
        if (m_thread.joinable() || m_done) throw std::runtime_error("load job already started");
        m_thread = std::thread([this] { run(); });
    }

    /// Wait up to `timeout` seconds; true when the load has ended (loaded, failed or cancelled).
    bool wait(double timeout) {
        std::unique_lock<std::mutex> lock(m_mutex);
        m_cv.wait_for(lock, std::chrono::duration<double>(timeout), [this] { return m_done; });
        if (m_done && m_thread.joinable()) {
            lock.unlock();
            m_thread.join();
        }
        return m_done;
    }

    void cancel() { m_cancel = true; }

    /// The loaded scene; the load's error (a SceneError, bad_alloc, ...) is raised instead.
    std::shared_ptr<mvpt::Scene> scene() {
        if (!wait(0.0)) throw std::runtime_error("the scene is still loading");
        if (m_error) std::rethrow_exception(m_error);
        return m_scene;
    }

private:
    void run() {
        std::shared_ptr<mvpt::Scene> scene;
        std::exception_ptr error;
        try {
            mvpt::LoadControlScope control({&m_cancel, m_every_view});
            scene = m_load();
        } catch (...) {
            error = std::current_exception();
        }
        std::lock_guard<std::mutex> lock(m_mutex);
        m_scene = std::move(scene);
        m_error = error;
        m_done = true;
        m_cv.notify_all();
    }

    Load m_load;
    bool m_every_view;
    std::atomic<bool> m_cancel{false};
    std::thread m_thread;
    std::mutex m_mutex;
    std::condition_variable m_cv;
    bool m_done = false;
    std::shared_ptr<mvpt::Scene> m_scene;
    std::exception_ptr m_error;
};

} // namespace mvpt_py
