#include "sim/journal.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/version.hpp"
#include "io/file_bytes.hpp"
#include "io/json_reader.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace vox::sim {
namespace {

constexpr const char* k_kind = "voxsculpt session journal";
constexpr int k_format = 1;

std::string fnv1a_hex(const std::vector<std::byte>& bytes)
{
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (const std::byte b : bytes) h = (h ^ static_cast<std::uint64_t>(b)) * 0x100000001b3ull;
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
    return text;
}

nlohmann::json header_json(const JournalHeader& h)
{
    return {{"journal", k_kind}, {"format", k_format},   {"program", h.program}, {"scene", h.scene},
            {"scene_fnv1a", h.scene_hash}, {"method", h.method}, {"level", h.level}};
}

/// The header line, checked against `expected`.
JournalHeader check_header(const nlohmann::json& j, const std::string& name, const JournalHeader& expected)
{
    if (!j.is_object() || j.value("journal", std::string()) != k_kind)
        throw file_error(name, "not a VoxSculpt session journal (its first line is not a journal header)");
    if (j.value("format", 0) != k_format)
        throw file_error(name, "journal format " + io::show(j.value("format", nlohmann::json())) + ", this program reads format " +
                                   std::to_string(k_format));
    JournalHeader h;
    try {
        h.program = j.at("program").get<std::string>();
        h.scene = j.at("scene").get<std::string>();
        h.scene_hash = j.at("scene_fnv1a").get<std::string>();
        h.method = j.at("method").get<std::string>();
        h.level = j.at("level").get<int>();
    } catch (const nlohmann::json::exception&) {
        throw file_error(name, "its header lacks program, scene, scene_fnv1a, method or level");
    }
    if (h.program != expected.program)
        throw file_error(name, "written by " + h.program + ", this is " + expected.program +
                                   ": a journal is resumed by the program version that wrote it");
    if (h.scene_hash != expected.scene_hash)
        throw file_error(name, "written for another scene: " + h.scene + " as it was then, not " + expected.scene +
                                   " as it is now (their contents differ)");
    if (h.method != expected.method || (h.level != expected.level && !expected.any_level))
        throw file_error(name, "written for the " + h.method + " method at level " + std::to_string(h.level) +
                                   "; this simulates " + expected.method + " at level " + std::to_string(expected.level) +
                                   " (give the same --solver and level)");
    return h;
}

JournalStroke parse_stroke(const nlohmann::json& j, const std::string& where)
{
    JournalStroke s;
    try {
        s.stroke = j.at("stroke").get<int>();
        s.frame = j.at("frame").get<int>();
        s.t_s = j.at("t_s").get<double>();
        s.cuts_before = j.at("cuts_before").get<std::size_t>();
        s.cuts = j.at("cuts");
    } catch (const nlohmann::json::exception&) {
        throw InputError(where + "a stroke line needs stroke, frame, t_s, cuts_before and cuts");
    }
    if (!s.cuts.is_array()) throw InputError(where + "cuts is not an array");
    if (s.frame < 0 || !(s.t_s >= 0.0)) throw InputError(where + "a negative frame or time");
    return s;
}

/// JOURNAL.state.a/.b: "VOXSTATE", the stroke (int32), the count (uint64), then the numbers
/// (doubles), in this machine's byte order.
constexpr char k_state_magic[8] = {'V', 'O', 'X', 'S', 'T', 'A', 'T', 'E'};

/// Even strokes' state goes to .a, odd strokes' to .b.
std::filesystem::path state_path(const std::filesystem::path& journal, int stroke)
{
    return journal.string() + (stroke % 2 == 0 ? ".state.a" : ".state.b");
}

/// The numbers of stroke `stroke`'s state file when it holds that stroke's; empty otherwise.
std::vector<double> read_state(const std::filesystem::path& journal, int stroke)
{
    if (stroke < 0) return {};
    std::ifstream in(state_path(journal, stroke), std::ios::binary);
    char magic[8];
    std::int32_t at = -1;
    std::uint64_t count = 0;
    if (!in.read(magic, 8) || std::memcmp(magic, k_state_magic, 8) != 0) return {};
    if (!in.read(reinterpret_cast<char*>(&at), sizeof at) || !in.read(reinterpret_cast<char*>(&count), sizeof count)) return {};
    std::error_code ec;
    const std::uint64_t size = std::filesystem::file_size(state_path(journal, stroke), ec);
    if (at != stroke || ec || size != 8 + sizeof at + sizeof count + count * sizeof(double)) return {};
    std::vector<double> numbers(count);
    if (!in.read(reinterpret_cast<char*>(numbers.data()), static_cast<std::streamsize>(count * sizeof(double)))) return {};
    return numbers;
}

} // namespace

JournalHeader journal_header(const std::filesystem::path& scene, const Method& method)
{
    return {program_version(), scene.string(), fnv1a_hex(io::read_file_bytes(scene.string())), method.name(), method.level()};
}

std::filesystem::path journal_path(const std::filesystem::path& output_dir)
{
    std::filesystem::path dir = output_dir;
    if (!dir.has_filename()) dir = dir.parent_path(); // "out/" is "out"
    return dir.string() + ".journal";
}

nlohmann::json Journal::cuts() const
{
    nlohmann::json all = nlohmann::json::array();
    for (const JournalStroke& s : strokes) {
        if (s.cuts_before > all.size())
            throw file_error(path.string(), "stroke " + std::to_string(s.stroke) + " begins after cut " + std::to_string(s.cuts_before) +
                                                ", but the strokes before it made " + std::to_string(all.size()));
        all.erase(all.begin() + static_cast<std::ptrdiff_t>(s.cuts_before), all.end());
        for (const auto& c : s.cuts) all.push_back(c);
    }
    return all;
}

Journal read_journal(const std::filesystem::path& path, const JournalHeader& expected)
{
    const std::string name = path.string();
    const std::vector<std::byte> bytes = io::read_file_bytes(name);
    const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    Journal out;
    out.path = path;
    std::size_t at = 0;
    int line = 0;
    while (at < text.size()) {
        const std::size_t end = text.find('\n', at);
        ++line;
        if (end == std::string_view::npos) { // written up to the process's death: left out
            out.torn_tail = true;
            break;
        }
        const nlohmann::json j = io::parse_json(text.substr(at, end - at), name + " line " + std::to_string(line));
        if (line == 1) out.header = check_header(j, name, expected);
        else out.strokes.push_back(parse_stroke(j, name + ": line " + std::to_string(line) + ": "));
        at = end + 1;
    }
    if (line == 0 || (line == 1 && out.torn_tail)) throw file_error(name, "not a VoxSculpt session journal (no header line)");
    if (out.torn_tail)
        log::warn("{}: its last line was cut off (the program stopped while writing it): resuming from stroke {}", name,
                  out.strokes.empty() ? 0 : out.strokes.back().stroke);
    (void)out.cuts(); // refuses strokes that do not follow one another
    out.motion = read_state(path, out.strokes.empty() ? -1 : out.strokes.back().stroke);
    return out;
}

void resume(Method& method, const Journal& journal)
{
    const std::string name = journal.path.string();
    if (method.cut_count() != 0) throw file_error(name, "the object already has cuts: a journal is resumed on an uncut object");
    if (journal.header.level != method.level()) { // written after the run moved between levels
        bool moved = false;
        try {
            moved = method.move_to_level(journal.header.level, io::PreconditionerChoice::automatic);
        } catch (const InputError& e) {
            throw file_error(name, "written at level " + std::to_string(journal.header.level) + ": " + e.what());
        }
        if (!moved)
            throw file_error(name, "written at level " + std::to_string(journal.header.level) + ", which the " + method.name() +
                                       " method cannot move to");
        log::info("{}: written at level {}: the run resumes there", name, journal.header.level);
    }
    try {
        method.replay_cuts(journal.cuts());
    } catch (const InputError& e) {
        throw file_error(name, std::string(e.what()) + " (the journal does not fit this object)");
    }
    if (journal.motion.empty()) {
        log::info("{}: no state of its last stroke beside it: the object starts at rest", name);
        return;
    }
    try {
        method.set_motion(journal.motion);
    } catch (const InputError& e) {
        log::warn("{}: {}: the object starts at rest", state_path(journal.path, journal.strokes.back().stroke).string(), e.what());
    }
}

JournalWriter::JournalWriter(std::filesystem::path path, const JournalHeader& header, const Method& method, int frame, double t_s)
    : m_path(std::move(path)), m_cuts(method.cut_count()), m_low(m_cuts)
{
    std::error_code ec;
    if (std::filesystem::exists(m_path, ec)) std::filesystem::rename(m_path, m_path.string() + ".previous", ec);
    for (const int slot : {0, 1}) // the state files go with it
        if (std::filesystem::exists(state_path(m_path, slot), ec))
            std::filesystem::rename(state_path(m_path, slot), state_path(m_path.string() + ".previous", slot), ec);
    if (m_cuts > 0) save_motion(method, 0);
    std::string first = header_json(header).dump() + '\n';
    if (m_cuts > 0)
        first += nlohmann::json{{"stroke", 0}, {"frame", frame}, {"t_s", t_s}, {"cuts_before", 0}, {"cuts", method.cuts_since(0)}}.dump() + '\n';
    try {
        write_atomically(m_path, [&](const std::filesystem::path& tmp) {
            std::ofstream out(tmp, std::ios::binary);
            out << first;
            out.flush();
            if (!out) throw file_error(m_path.string(), "cannot write the session journal");
        });
    } catch (const std::filesystem::filesystem_error& e) {
        throw file_error(m_path.string(), std::string("cannot write the session journal: ") + e.code().message());
    }
    m_fd = ::open(m_path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
    if (m_fd < 0) throw file_error(m_path.string(), std::string("cannot open the session journal: ") + std::strerror(errno));
    ::fdatasync(m_fd);
    // The new name itself made durable: the folder's entry.
    const std::filesystem::path folder = m_path.has_parent_path() ? m_path.parent_path() : std::filesystem::path(".");
    if (const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dir >= 0) {
        ::fsync(dir);
        ::close(dir);
    }
}

JournalWriter::~JournalWriter()
{
    if (m_fd >= 0) ::close(m_fd);
}

void JournalWriter::rewound(const Method& method) { m_low = std::min(m_low, method.cut_count()); }

void JournalWriter::end_stroke(const Method& method, int frame, double t_s)
{
    const std::size_t count = method.cut_count();
    const std::size_t from = std::min({m_cuts, m_low, count});
    if (from == m_cuts && count == m_cuts) return; // the stroke changed no cut: nothing to keep
    save_motion(method, m_strokes + 1); // before the line: whichever line is last has its state
    append({{"stroke", ++m_strokes}, {"frame", frame}, {"t_s", t_s}, {"cuts_before", from}, {"cuts", method.cuts_since(from)}});
    m_cuts = m_low = count;
}

void JournalWriter::save_motion(const Method& method, int stroke_number)
{
    if (m_failed) return;
    const std::vector<double> numbers = method.motion();
    const std::int32_t stroke = stroke_number;
    const std::uint64_t count = numbers.size();
    try {
        write_atomically(state_path(m_path, stroke_number), [&](const std::filesystem::path& tmp) {
            const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
            if (fd < 0) throw file_error(tmp.string(), std::strerror(errno));
            bool ok = ::write(fd, k_state_magic, 8) == 8 && ::write(fd, &stroke, sizeof stroke) == sizeof stroke &&
                      ::write(fd, &count, sizeof count) == sizeof count;
            const auto* bytes = reinterpret_cast<const char*>(numbers.data());
            std::size_t done = 0, total = numbers.size() * sizeof(double);
            while (ok && done < total) {
                const ssize_t n = ::write(fd, bytes + done, total - done);
                if (n < 0 && errno == EINTR) continue;
                ok = n > 0;
                if (ok) done += static_cast<std::size_t>(n);
            }
            ok = ok && ::fdatasync(fd) == 0; // on disk before it replaces the last one
            ::close(fd);
            if (!ok) throw file_error(tmp.string(), std::strerror(errno));
        });
    } catch (const InputError& e) {
        m_failed = true;
        log::warn("cannot write the session journal's state ({}); the session goes on without it", e.what());
    }
}

void JournalWriter::append(const nlohmann::json& line)
{
    if (m_failed) return;
    const std::string text = line.dump() + '\n';
    std::size_t done = 0;
    while (done < text.size()) {
        const ssize_t n = ::write(m_fd, text.data() + done, text.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        done += static_cast<std::size_t>(n);
    }
    if (done != text.size() || ::fdatasync(m_fd) != 0) {
        m_failed = true;
        log::warn("{}: cannot write the session journal ({}); the session goes on without it", m_path.string(), std::strerror(errno));
    }
}

bool StrokeEnds::after_frame(const FrameStats& frame)
{
    bool cut_now = false;
    std::vector<Eigen::Vector3d> at;
    for (const ToolFrame& t : frame.tools.tools) {
        cut_now = cut_now || t.cut;
        if (t.placed) at.push_back(t.position_mm);
    }
    bool ended = m_cutting && !cut_now; // a cut ended
    m_cutting = cut_now;
    constexpr double k_still_mm = 0.1, k_pause_s = 0.5;
    bool moved = at.size() != m_still_at.size();
    for (std::size_t k = 0; !moved && k < at.size(); ++k) moved = (at[k] - m_still_at[k]).norm() > k_still_mm;
    if (moved) {
        m_still_at = std::move(at);
        m_still_since = frame.t_s;
        m_reported_still = false;
    } else if (!m_reported_still && frame.t_s - m_still_since >= k_pause_s - 1e-9) {
        m_reported_still = true;
        ended = true; // a pause
    }
    return ended;
}

} // namespace vox::sim
