#pragma once
// The runner of an editor script (weft/editor/script.h) inside the editor's frame loop
// (editor.cpp): the commands run between displayed frames, through the same requests the panels
// make, so that a script tests what a person would do.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <utility>

#include "weft/editor/script.h"
#include "weft/editor/session.h"

namespace weft::editor {

/// Runs a script's commands between displayed frames. Commands that change something (set, the
/// play controls) end the script's turn: the change is made by the panels during the next frame,
/// and the commands after it see its result. `frame N` waits for the Nth displayed frame.
class ScriptRunner {
public:
    explicit ScriptRunner(Script script) : script_(std::move(script)) {}

    enum class Outcome : unsigned char { next_frame, quit, failed };
    /// Writes the last displayed frame, with the panels, to a PNG file.
    using Screenshot = std::function<void(const std::filesystem::path&)>;

    /// Runs commands until one ends the script's turn. `shown`: frames displayed so far.
    Outcome run(Session& session, int shown, const Screenshot& shot, std::ostream& out, std::ostream& err);

    [[nodiscard]] int expectations() const { return expectations_; }

private:
    /// Commands after an `open` are checked against the scene open when they run.
    bool checked(Session& session, std::size_t k, std::ostream& err);
    /// An `expect`: the world, and the last step where it reports the value, use the expected one.
    bool expect(Session& session, const ScriptCommand& c, const std::string& where, std::ostream& err);

    Script script_;
    std::size_t next_ = 0;
    int expectations_ = 0;
};

/// Creates the folders above `file` (a screenshot, a saved scene); throws weft::Error naming the
/// folder when it cannot.
void make_parent(const std::filesystem::path& file);

}  // namespace weft::editor
