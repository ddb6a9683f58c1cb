// A scene's load on a thread of its own, which Python waits for with the GIL released: a
// signal handler (Ctrl-C) then runs between the waits and cancels the load within a fraction
// of a second, where a load of 10^5 rig views holding the GIL answered only once done.
#pragma once

#include "mvpt/loader/load_control.h"
#include "mvpt/loader/load_scene.h"
#include "job_thread.h"

#include <atomic>
#include <exception>
#include <functional>
#include <memory>
#include <stdexcept>

namespace mvpt_py {

class LoadJob {
public:
    using Load = std::function<std::unique_ptr<mvpt::Scene>()>;

    /// `every_view_rendered`: the caller renders all the views at once (LoadControl).
    LoadJob(Load load, bool every_view_rendered) : m_load(std::move(load)), m_every_view(every_view_rendered) {}
    ~LoadJob() { m_cancel = true; } // (m_job, the last member, then joins the thread)

    void start() { m_job.start([this] { run(); }, "load job"); }
    /// Wait up to `timeout` seconds; true when the load has ended (loaded, failed or cancelled).
    bool wait(double timeout) { return m_job.wait(timeout); }
    void cancel() { m_cancel = true; }

    /// The loaded scene; the load's error (a SceneError, bad_alloc, ...) is raised instead.
    std::shared_ptr<mvpt::Scene> scene() {
        if (!m_job.wait(0.0)) throw std::runtime_error("the scene is still loading");
        if (m_error) std::rethrow_exception(m_error);
        return m_scene;
    }

private:
    /// On the job's thread; what it leaves is read only once the job is done.
    void run() {
        try {
            mvpt::LoadControlScope control({&m_cancel, m_every_view});
            m_scene = m_load();
        } catch (...) {
            m_error = std::current_exception();
        }
    }

    Load m_load;
    bool m_every_view;
    std::atomic<bool> m_cancel{false};
    std::shared_ptr<mvpt::Scene> m_scene;
    std::exception_ptr m_error;
    JobThread m_job;
};

} // namespace mvpt_py
