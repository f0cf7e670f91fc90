#pragma once
// A ring of fixed capacity from one writer thread to one reader thread, neither ever waiting,
// locking or allocating after construction: the haptic loop leaves each tick's reading and force
// in it, the simulation thread takes them once a frame. A full ring drops the newest value and
// counts it (the reader fell behind by the whole capacity).

#include <atomic>
#include <cstdint>
#include <vector>

namespace vox::haptics {

template <class T> class TickRing {
public:
    explicit TickRing(std::size_t capacity) : m_slots(capacity) {}

    /// Writer: appends `value`; false (and counted) when the ring is full.
    bool push(const T& value) noexcept
    {
        const std::uint64_t head = m_head.load(std::memory_order_relaxed);
        if (head - m_tail.load(std::memory_order_acquire) >= m_slots.size()) {
            m_dropped.fetch_add(1, std::memory_order_relaxed);
            return false;
        }
        m_slots[head % m_slots.size()] = value;
        m_head.store(head + 1, std::memory_order_release);
        return true;
    }
    /// Reader: values waiting.
    [[nodiscard]] std::size_t size() const noexcept
    {
        return static_cast<std::size_t>(m_head.load(std::memory_order_acquire) - m_tail.load(std::memory_order_relaxed));
    }
    /// Reader: the oldest value waiting (size() > 0), and taking it.
    [[nodiscard]] const T& front() const noexcept { return m_slots[m_tail.load(std::memory_order_relaxed) % m_slots.size()]; }
    void pop() noexcept { m_tail.store(m_tail.load(std::memory_order_relaxed) + 1, std::memory_order_release); }
    /// Values the writer dropped because the ring was full.
    [[nodiscard]] std::uint64_t dropped() const noexcept { return m_dropped.load(std::memory_order_relaxed); }

private:
    std::vector<T> m_slots;
    std::atomic<std::uint64_t> m_head{0}, m_tail{0}, m_dropped{0};
};

} // namespace vox::haptics
