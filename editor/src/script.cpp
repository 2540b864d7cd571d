// Parsing and checking of editor scripts (see script.h).
#include "weft/editor/script.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "weft/error.h"
#include "weft/world_limits.h"
#include "weft/parameters.h"

namespace weft::editor {
namespace {

struct Spelling {
    std::string_view name;
    ScriptCommand::Kind kind;
    int arguments;
};
constexpr Spelling kCommands[] = {
    {"frame", ScriptCommand::Kind::frame, 1},           {"set", ScriptCommand::Kind::set, 2},
    {"expect", ScriptCommand::Kind::expect, 2},         {"pause", ScriptCommand::Kind::pause, 0},
    {"play", ScriptCommand::Kind::play, 0},             {"step", ScriptCommand::Kind::step, 0},
    {"reset", ScriptCommand::Kind::reset, 0},           {"timescale", ScriptCommand::Kind::timescale, 1},
    {"open", ScriptCommand::Kind::open, 1},             {"record", ScriptCommand::Kind::record, 1},
    {"stop", ScriptCommand::Kind::stop, 0},             {"cells", ScriptCommand::Kind::cells, 3},
    {"cook", ScriptCommand::Kind::cook, 3},             {"preset", ScriptCommand::Kind::preset, 2},
    {"show", ScriptCommand::Kind::show, 2},             {"screenshot", ScriptCommand::Kind::screenshot, 1},
    {"save", ScriptCommand::Kind::save, 1},             {"grab", ScriptCommand::Kind::grab, 2},
    {"drag", ScriptCommand::Kind::drag, 2},             {"held", ScriptCommand::Kind::held, 1},
    {"release", ScriptCommand::Kind::release, 0},       {"pin", ScriptCommand::Kind::pin, 2},
    {"quit", ScriptCommand::Kind::quit, 0},
};

constexpr std::string_view kDisplayToggles[] = {"wireframe", "normals", "contacts", "pins"};

// "true"/"on"/"1" or "false"/"off"/"0", or an error naming the line and the word.
bool on_off(const std::string& w, const std::string& where, const std::string& what) {
    if (w == "on" || w == "true" || w == "1") return true;
    if (w == "off" || w == "false" || w == "0") return false;
    throw Error(where + what + " expects on or off, got '" + w + "'");
}

// A number in `range` written alone, or an error naming the line and the word.
double number_in(const std::string& w, const ParameterRange& range, const std::string& where, const std::string& what) {
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
    if (ec != std::errc{} || ptr != w.data() + w.size() || !range.contains(v)) throw Error(where + what + ", got '" + w + "'");
    return v;
}
double number_in(const std::string& w, double lo, double hi, const std::string& where, const std::string& what) {
    return number_in(w, ParameterRange{lo, hi}, where, what);
}

// `cook FIELD VALUE`: a number in the range of the scene key it re-cooks (weft/parameters.h).
double cook_number(const std::string& w, const weft::Parameter& p, const std::string& where) {
    const std::string what = p.unit.empty() ? "a " + std::string(p.name) : std::string(p.unit);
    return number_in(w, p.range, where, "cook " + std::string(p.name) + " expects " + what + " in " + p.range.text());
}

std::string command_list() {
    std::string out;
    for (const Spelling& s : kCommands) out += (out.empty() ? "" : ", ") + std::string(s.name);
    return out;
}

std::vector<std::string> words_of(std::string_view line) {
    std::vector<std::string> words;
    std::istringstream in{std::string(line)};
    for (std::string w; in >> w;) words.push_back(w);
    return words;
}

}  // namespace

Script parse_script(std::string_view text, const std::string& name) {
    Script script;
    script.name = name;
    int line_number = 0;
    int last_frame = 0;
    std::size_t start = 0;
    while (start <= text.size()) {
        const std::size_t end = std::min(text.find('\n', start), text.size());
        std::string_view line = text.substr(start, end - start);
        start = end + 1;
        ++line_number;
        if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
        const std::vector<std::string> words = words_of(line);
        if (words.empty()) {
            if (end == text.size()) break;
            continue;
        }
        const std::string where = name + ":" + std::to_string(line_number) + ": ";
        const Spelling* spelling = nullptr;
        for (const Spelling& s : kCommands)
            if (s.name == words[0]) spelling = &s;
        if (spelling == nullptr)
            throw Error(where + "unknown command '" + words[0] + "' (commands: " + command_list() + ")");
        const int given = static_cast<int>(words.size()) - 1;
        if (given != spelling->arguments)
            throw Error(where + "'" + words[0] + "' takes " + std::to_string(spelling->arguments) +
                        (spelling->arguments == 1 ? " argument" : " arguments") + ", got " + std::to_string(given));
        ScriptCommand c;
        c.kind = spelling->kind;
        c.line = line_number;
        switch (c.kind) {
            case ScriptCommand::Kind::frame: {
                const std::string& w = words[1];
                const auto [ptr, ec] = std::from_chars(w.data(), w.data() + w.size(), c.frame);
                if (ec != std::errc{} || ptr != w.data() + w.size() || c.frame < 1 || c.frame > 100'000'000)
                    throw Error(where + "frame expects a frame count in [1, 100000000], got '" + w + "'");
                if (c.frame <= last_frame)
                    throw Error(where + "frame " + w + " does not come after frame " + std::to_string(last_frame));
                last_frame = c.frame;
                break;
            }
            case ScriptCommand::Kind::timescale: {
                const std::string& w = words[1];
                const auto [ptr, ec] = std::from_chars(w.data(), w.data() + w.size(), c.number);
                if (ec != std::errc{} || ptr != w.data() + w.size() || !(c.number >= 0.01 && c.number <= 100.0))
                    throw Error(where + "timescale expects a number in [0.01, 100], got '" + w + "'");
                break;
            }
            case ScriptCommand::Kind::set:
            case ScriptCommand::Kind::expect:
                c.key = words[1];
                c.text = words[2];
                break;
            case ScriptCommand::Kind::cells: {
                c.key = words[1];
                int* targets[2] = {&c.cells_x, &c.cells_y};
                for (int k = 0; k < 2; ++k) {
                    const std::string& w = words[2 + static_cast<std::size_t>(k)];
                    const auto [ptr, ec] = std::from_chars(w.data(), w.data() + w.size(), *targets[k]);
                    const ParameterRange& range = parameter("cloth.mesh.grid", "cells").range;
                    if (ec != std::errc{} || ptr != w.data() + w.size() || !range.contains(*targets[k]))
                        throw Error(where + "cells expects two cell counts in " + range.integer_text() + ", got '" + w + "'");
                }
                break;
            }
            case ScriptCommand::Kind::cook:
                c.key = words[1];
                c.text = words[2];
                if (c.text == "density")
                    c.number = cook_number(words[3], parameter("cloth", "density"), where);
                else if (c.text == "scale")
                    c.number = cook_number(words[3], parameter("cloth.mesh", "scale"), where);
                else if (c.text == "flat_rest_bending")
                    c.number = on_off(words[3], where, "cook flat_rest_bending") ? 1.0 : 0.0;
                else
                    throw Error(where + "cook: unknown field '" + c.text +
                                "' (fields: density, scale, flat_rest_bending; cells has its own command)");
                break;
            case ScriptCommand::Kind::preset:
                c.key = words[1];
                c.text = words[2];
                break;
            case ScriptCommand::Kind::show: {
                c.key = words[1];
                bool known = false;
                for (const std::string_view t : kDisplayToggles) known = known || t == c.key;
                if (!known) throw Error(where + "show: unknown display '" + c.key + "' (wireframe, normals, contacts, pins)");
                c.number = on_off(words[2], where, "show " + c.key) ? 1.0 : 0.0;
                break;
            }
            case ScriptCommand::Kind::grab:
            case ScriptCommand::Kind::drag:
            case ScriptCommand::Kind::pin:
                c.x = number_in(words[1], 0.0, 16384.0, where, (words[0] + " expects picture pixels x y in [0, 16384]").c_str());
                c.y = number_in(words[2], 0.0, 16384.0, where, (words[0] + " expects picture pixels x y in [0, 16384]").c_str());
                break;
            case ScriptCommand::Kind::held:
                c.x = number_in(words[1], 0.0, 100.0, where, "held expects a distance in [0, 100] m");
                break;
            case ScriptCommand::Kind::screenshot:
            case ScriptCommand::Kind::save:
            case ScriptCommand::Kind::open:
            case ScriptCommand::Kind::record:
                c.text = words[1];
                break;
            default:
                break;
        }
        script.commands.push_back(std::move(c));
        if (end == text.size()) break;
    }
    return script;
}

Script read_script(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Error("script " + file.string() + ": cannot be read");
    check_file_size(file, kMaxTextFileBytes, "script");
    std::ostringstream text;
    text << in.rdbuf();
    return parse_script(text.str(), file.string());
}

void check_command(const std::string& script_name, ScriptCommand& c, const ParameterTable& table) {
    const std::string where = script_name + ":" + std::to_string(c.line) + ": ";
    const Parameter* p = table.find(c.key);
    if (p == nullptr)
        throw Error(where + "unknown parameter '" + c.key + "' (the keys are listed in docs/editor.md)");
    try {
        c.number = ParameterTable::parse_value(*p, c.text);
    } catch (const Error& e) {
        throw Error(where + e.what());
    }
    c.checked = true;
}

void check_script(Script& script, const ParameterTable& table) {
    for (ScriptCommand& c : script.commands) {
        // After an `open`, the keys belong to another scene: checked when they run.
        if (c.kind == ScriptCommand::Kind::open) break;
        if (c.kind == ScriptCommand::Kind::set || c.kind == ScriptCommand::Kind::expect)
            check_command(script.name, c, table);
    }
}

}  // namespace weft::editor
