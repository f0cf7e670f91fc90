#pragma once
// The viewer's undo: the method's state before each stroke, the newest last, at most a fixed
// number kept (each holds the solver's state, and the branched grid's cut count to replay to).

#include "sim/method.hpp"

#include <memory>
#include <vector>

namespace vox::sim {

class UndoHistory {
public:
    explicit UndoHistory(std::size_t capacity = 20) : m_capacity(capacity) {}

    /// Remembers `method` as it is, before a stroke; the oldest is dropped beyond the capacity.
    /// False when the method cannot go back (Method::checkpoint is null): nothing is kept.
    bool before_stroke(const Method& method);
    /// Puts `method` back to before the last stroke remembered and forgets it; false when there is
    /// none. The tools' contact episodes should be reset after it (ToolPolicy::reset).
    bool undo(Method& method);
    /// Forgets everything (after the method was replaced, e.g. at another level).
    void clear() { m_states.clear(); }
    [[nodiscard]] std::size_t size() const { return m_states.size(); }

private:
    std::size_t m_capacity;
    std::vector<std::unique_ptr<Checkpoint>> m_states;
};

} // namespace vox::sim
