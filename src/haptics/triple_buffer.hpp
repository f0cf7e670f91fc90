#pragma once
// One writer (the simulation thread) publishes values, one reader (the haptic thread) always
// gets the newest complete one, neither ever waits, locks or allocates: three slots, the writer
// fills its own, then swaps it with the middle one and flags it fresh; the reader swaps the middle
// one with its own when the flag says there is something new. T is built once, up front, and
// reused (a surface snapshot keeps its capacity).

#include <atomic>
#include <cstdint>
#include <utility>

namespace vox::haptics {

template <class T> class TripleBuffer {
public:
    TripleBuffer() = default;
    explicit TripleBuffer(const T& initial) : m_slots{initial, initial, initial} {}

    /// The writer's slot, to fill before publish().
    [[nodiscard]] T& write_slot() noexcept { return m_slots[m_write]; }
    /// Makes the writer's slot the newest value.
    void publish() noexcept
    {
        const std::uint8_t previous = m_middle.exchange(static_cast<std::uint8_t>(m_write | k_fresh), std::memory_order_acq_rel);
        m_write = previous & k_index;
    }
    /// Takes the newest published value if there is one; true when it changed.
    bool update() noexcept
    {
        if (!(m_middle.load(std::memory_order_relaxed) & k_fresh)) return false;
        const std::uint8_t previous = m_middle.exchange(m_read, std::memory_order_acq_rel);
        m_read = previous & k_index;
        return true;
    }
    /// The reader's current value.
    [[nodiscard]] const T& read_slot() const noexcept { return m_slots[m_read]; }
    /// The newest value: update() then read_slot().
    [[nodiscard]] const T& latest() noexcept
    {
        update();
        return read_slot();
    }

private:
    static constexpr std::uint8_t k_index = 3, k_fresh = 4;
    T m_slots[3]{};
    std::uint8_t m_write = 0, m_read = 1;
    std::atomic<std::uint8_t> m_middle{2};
};

} // namespace vox::haptics
