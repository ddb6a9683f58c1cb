// A task on a thread of its own that Python waits for in short slices with the GIL released,
// so that its signal handlers (Ctrl-C) run between them: the module's renders and loads.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

namespace mvpt_py {

class JobThread {
public:
    JobThread() = default;
    JobThread(const JobThread &) = delete;
    JobThread &operator=(const JobThread &) = delete;
    /// Joins the thread: its owner asks the task to stop first, and declares this member last
    /// so that it goes before what the task uses.
    ~JobThread() {
        if (m_thread.joinable()) m_thread.join();
    }

    /// Runs `task` on the thread, then marks the job done; `what` names the job in errors.
    void start(std::function<void()> task, const char *what) {
        std::lock_guard<std::mutex> lock(m_mutex);
        if (m_thread.joinable() || m_done) throw std::runtime_error(std::string(what) + " already started");
        m_thread = std::thread([this, task = std::move(task)] {
            task();
            finish();
        });
    }

    /// Marks the job done (a job that ran on the caller's thread instead says so itself).
    void finish() {
        {
            std::lock_guard<std::mutex> lock(m_mutex);
            m_done = true;
        }
        m_cv.notify_all();
    }

    /// Waits up to `timeout` seconds; true when the job is done (its thread then joined).
    bool wait(double timeout) {
        std::unique_lock<std::mutex> lock(m_mutex);
        m_cv.wait_for(lock, std::chrono::duration<double>(timeout), [this] { return m_done; });
        if (m_done && m_thread.joinable()) {
            lock.unlock();
            m_thread.join();
        }
        return m_done;
    }

    bool done() {
        std::lock_guard<std::mutex> lock(m_mutex);
        return m_done;
    }
    /// Started (on its thread or by the caller).
    bool started() {
        std::lock_guard<std::mutex> lock(m_mutex);
        return m_thread.joinable() || m_done;
    }

private:
    std::mutex m_mutex;
    std::condition_variable m_cv;
    bool m_done = false;
    std::thread m_thread;
};

} // namespace mvpt_py
