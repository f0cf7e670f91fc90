#include "sim/undo_history.hpp"

namespace vox::sim {

bool UndoHistory::before_stroke(const Method& method)
{
    std::unique_ptr<Checkpoint> c = method.checkpoint();
    if (!c) return false;
    m_states.push_back(std::move(c));
    if (m_states.size() > m_capacity) m_states.erase(m_states.begin());
    return true;
}

bool UndoHistory::undo(Method& method)
{
    if (m_states.empty()) return false;
    method.restore(*m_states.back());
    m_states.pop_back();
    return true;
}

} // namespace vox::sim
