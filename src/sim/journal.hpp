#pragma once
// Session journals (docs/journal.md): a viewer session or device run written down stroke by
// stroke, beside its output, so that a crash, a killed process or a run the solver stops loses at
// most the stroke under way. Each stroke's line holds the cuts it made as the method records them
// (Method::cuts_since: results, not tool motions), appended and synced to disk when the stroke
// ends; resuming replays them on the object at rest, no solve needed.
//
// The file: JSON Lines. The first line is the header (program version, scene file and a hash of
// its bytes, method, level); then one line per stroke: {"stroke", "frame", "t_s", "cuts_before",
// "cuts"}. "cuts_before" is how many cuts the method had when the stroke's cuts began: fewer than
// the journal's lines made after an undo, which drops the rest. A last line cut off by the process
// dying while writing it is left out when reading.
//
// Beside it, JOURNAL.state.a and JOURNAL.state.b hold how the object moved (Method::motion:
// positions, velocities, water, plastic strain) at the ends of the last two strokes, odd and even:
// each written, synced and renamed into place before its stroke's line, so whichever line is last
// has its state, and a resumed session goes on as it was, not from rest.

#include "sim/frame_loop.hpp"
#include "sim/method.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace vox::sim {

/// What a journal must match to be resumed.
struct JournalHeader {
    std::string program;      ///< program_version() of the program that wrote it
    std::string scene;        ///< the scene file, as given
    std::string scene_hash;   ///< FNV-1a (64 bits, hex) of the scene file's bytes
    std::string method;       ///< Method::name()
    int level = 0;            ///< Method::level()
    /// Reading: a journal of another level is accepted (a run that moves between levels,
    /// "levels": "auto"), and resume() moves the method to it.
    bool any_level = false;
};

/// The header for `method` simulating the scene file `scene` with this program. Throws InputError
/// when the scene file cannot be read.
[[nodiscard]] JournalHeader journal_header(const std::filesystem::path& scene, const Method& method);

/// Where the journal of a run or session writing into `output_dir` goes: beside it, OUTPUT.journal.
[[nodiscard]] std::filesystem::path journal_path(const std::filesystem::path& output_dir);

struct JournalStroke {
    int stroke = 0;              ///< from 1
    int frame = 0;               ///< the frame it ended with
    double t_s = 0.0;            ///< simulated time at that frame's end
    std::size_t cuts_before = 0; ///< the method's cut count where its cuts begin
    nlohmann::json cuts;         ///< Method::cuts_since(cuts_before) when it ended
};

struct Journal {
    std::filesystem::path path;
    JournalHeader header;
    std::vector<JournalStroke> strokes;
    bool torn_tail = false; ///< its last line was cut off (the process died writing it) and left out
    /// Method::motion() at the last stroke's end, from JOURNAL.state.a or .b; empty when that file
    /// is missing or belongs to another stroke (the object then starts at rest).
    std::vector<double> motion;

    /// The cuts of every stroke in the order the method must make them, undos applied.
    [[nodiscard]] nlohmann::json cuts() const;
};

/// Reads the journal at `path`. Throws InputError naming the file when it is not a journal, is
/// damaged before its last line, or was written by another program version, for another scene (its
/// bytes differ), another method or level than `expected`.
[[nodiscard]] Journal read_journal(const std::filesystem::path& path, const JournalHeader& expected);

/// Makes the journal's cuts on `method` (which has none yet), at the journal's level, and puts
/// back how it moved: the object as the journal's last stroke left it. Throws InputError "JOURNAL: problem" for cuts that do not
/// fit the object; a state that does not fit is said and left out (the object starts at rest).
void resume(Method& method, const Journal& journal);

/// Writes a journal. Not thread-safe: the simulation thread owns it.
class JournalWriter {
public:
    /// Starts a journal at `path` (its folder made when missing) for `method` as it is now: cuts it
    /// already has (resumed, or kept across a level change) go in a first line, so the journal alone
    /// restores the object; `frame` and `t_s` say when (a resumed run goes on from there). A journal
    /// already there is kept as PATH.previous. Throws InputError when the file cannot be written.
    JournalWriter(std::filesystem::path path, const JournalHeader& header, const Method& method, int frame = 0, double t_s = 0.0);
    ~JournalWriter();
    JournalWriter(const JournalWriter&) = delete;
    JournalWriter& operator=(const JournalWriter&) = delete;

    /// The method went back (undo): the next line drops the cuts past its count.
    void rewound(const Method& method);
    /// A stroke ends with frame `frame` (time `t_s`): when it changed the cuts, its line is written
    /// and synced before this returns. A write that fails is said once and the session goes on.
    void end_stroke(const Method& method, int frame, double t_s);

    [[nodiscard]] const std::filesystem::path& path() const { return m_path; }
    /// Lines written after the header.
    [[nodiscard]] int strokes() const { return m_strokes; }

private:
    void append(const nlohmann::json& line);
    /// The state file of stroke `stroke`, before its line.
    void save_motion(const Method& method, int stroke);

    std::filesystem::path m_path;
    int m_fd = -1;
    std::size_t m_cuts = 0; ///< the method's cut count at the last line
    std::size_t m_low = 0;  ///< the lowest it has been since (an undo)
    int m_strokes = 0;
    bool m_failed = false;
};

/// When a device-driven stroke ends, without a button to say so: a tool that cut stops cutting,
/// or the placed tools hold still (within 0.1 mm) for half a second.
class StrokeEnds {
public:
    /// True when the stroke ends with this frame.
    bool after_frame(const FrameStats& frame);

private:
    bool m_cutting = false;
    std::vector<Eigen::Vector3d> m_still_at;
    double m_still_since = 0.0;
    bool m_reported_still = false;
};

} // namespace vox::sim
