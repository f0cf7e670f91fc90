#include "haptics/haptic_loop.hpp"

#include <pthread.h>
#include <sched.h>

#include <chrono>

namespace vox::haptics {

HapticLoop::HapticLoop(std::vector<HapticChannel> channels, std::size_t capacity)
{
    m_channels.reserve(channels.size());
    for (HapticChannel& c : channels)
        m_channels.push_back({c.device, std::move(c.model), std::move(c.prepare), ForceSafety(c.safety), {}, Eigen::Vector3d::Zero()});
    m_timings.period_error_ms.resize(capacity);
    m_timings.force_us.resize(capacity);
    m_timings.work_us.resize(capacity);
}

HapticLoop::HapticLoop(Device& device, ForceModel model, const SafetySettings& safety, std::size_t capacity)
    : HapticLoop(std::vector<HapticChannel>{{&device, std::move(model), safety, {}}}, capacity)
{
}

HapticLoop::~HapticLoop() { stop(); }

Eigen::Vector3d HapticLoop::tick(double t_s) noexcept
{
    using clock = std::chrono::steady_clock;
    const auto begin = clock::now();
    m_last_t_s = t_s;
    for (Served& c : m_channels) {
        c.device->read(t_s, c.state);
        if (c.device->fault()) c.safety.hold_off(t_s); // no jolt when it comes back
        double age = 0.0;
        Eigen::Vector3d f = Eigen::Vector3d::Zero();
        try {
            f = c.model(c.state, age);
        } catch (...) { // a model that throws yields no force rather than ending the loop
            age = 1e9;
        }
        c.force = c.safety.filter(f, t_s, age);
        c.device->send(c.force, Eigen::Vector3d::Zero());
    }
    const auto sent = clock::now();
    for (Served& c : m_channels) {
        if (!c.prepare) continue;
        try {
            c.prepare(c.state);
        } catch (...) { // as a model's: the next tick measures for itself
        }
    }
    m_last_force_us = std::chrono::duration<double, std::micro>(sent - begin).count();
    m_last_work_us = std::chrono::duration<double, std::micro>(clock::now() - begin).count();
    return m_channels.empty() ? Eigen::Vector3d::Zero() : m_channels.front().force;
}

void HapticLoop::start()
{
    if (m_running.exchange(true)) return;
    m_recorded = 0;
    m_start = m_previous = std::chrono::steady_clock::now();
    // A device whose vendor runs the servo thread ticks the loop from it: one clock for all.
    for (Served& c : m_channels)
        if (c.device->run_servo(&HapticLoop::servo_tick, this)) {
            m_servo = c.device;
            return;
        }
    m_thread = std::thread([this] { run(); });
}

void HapticLoop::servo_tick(void* self) noexcept
{
    auto* loop = static_cast<HapticLoop*>(self);
    const auto now = std::chrono::steady_clock::now();
    loop->tick(std::chrono::duration<double>(now - loop->m_start).count());
    loop->record(now);
}

void HapticLoop::record(std::chrono::steady_clock::time_point now) noexcept
{
    if (m_recorded < m_timings.force_us.size()) {
        m_timings.period_error_ms[m_recorded] = std::abs(std::chrono::duration<double, std::milli>(now - m_previous).count() - 1.0);
        m_timings.force_us[m_recorded] = m_last_force_us;
        m_timings.work_us[m_recorded] = m_last_work_us;
        ++m_recorded;
    }
    m_previous = now;
}

void HapticLoop::stop()
{
    if (!m_running.exchange(false)) return;
    if (m_servo) m_servo->stop_servo();
    m_servo = nullptr;
    if (m_thread.joinable()) m_thread.join();
    m_timings.period_error_ms.resize(m_recorded);
    m_timings.force_us.resize(m_recorded);
    m_timings.work_us.resize(m_recorded);
}

void HapticLoop::run()
{
    sched_param p{};
    p.sched_priority = sched_get_priority_max(SCHED_FIFO);
    m_timings.realtime_priority = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0;
    using clock = std::chrono::steady_clock;
    const auto period = std::chrono::microseconds(1000);
    auto deadline = m_start + period;
    while (m_running.load(std::memory_order_relaxed)) {
        // Sleep until shortly before the deadline, then spin: sleeping alone wakes up late.
        std::this_thread::sleep_until(deadline - std::chrono::microseconds(150));
        while (clock::now() < deadline) {
        }
        const auto now = clock::now();
        tick(std::chrono::duration<double>(now - m_start).count());
        record(now);
        deadline += period;
        if (deadline < now) deadline = now + period; // fell behind by a whole period: do not burst
    }
}

} // namespace vox::haptics
