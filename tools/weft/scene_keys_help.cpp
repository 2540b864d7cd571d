// `weft help scene-keys` (see scene_keys_help.h): the parameter table as text and as Markdown.
#include "scene_keys_help.h"

#include <algorithm>

#include "weft/parameters.h"

namespace weft::cli {
namespace {

std::string_view type_name(ParameterType type) {
    switch (type) {
        case ParameterType::Real: return "number";
        case ParameterType::Integer: return "integer";
        case ParameterType::Boolean: return "boolean";
        case ParameterType::Choice: return "string";
        case ParameterType::Vector: return "[x, y, z]";
        case ParameterType::CellCounts: return "[nx, ny]";
        case ParameterType::String: return "string";
        case ParameterType::Table: return "table";
        case ParameterType::TableArray: return "array of tables";
        case ParameterType::IndexList: return "array of integers";
        case ParameterType::Box: return "{ min = [x, y, z], max = [x, y, z] }";
    }
    return "";
}

std::string_view effect_name(ParameterEffect effect) {
    switch (effect) {
        case ParameterEffect::Live: return "live";
        case ParameterEffect::Recook: return "re-cook";
        case ParameterEffect::Rebuild: return "rebuild";
    }
    return "";
}

// "sphere, capsule", or "all" for a key every collider has.
std::string shapes_text(const Parameter& p) {
    if (p.shapes == 0) return "all";
    const auto names = parameter("collider", "shape").choices;
    std::string out;
    for (std::size_t s = 0; s < names.size(); ++s)
        if ((p.shapes & (1U << s)) != 0) out.append(out.empty() ? "" : ", ").append(names[s]);
    return out;
}

// Markdown code for a quoted word and lists of them: `"float"`, `"double"`.
std::string code_quoted(const std::string& text) {
    std::string out;
    bool in_quote = false;
    for (const char c : text) {
        if (c == '"' && !in_quote) out += '`';
        out += c;
        if (c == '"' && in_quote) out += '`';
        if (c == '"') in_quote = !in_quote;
    }
    return out;
}

std::string cell(const std::string& text) { return text.empty() ? "—" : text; }

// `text` broken at spaces into lines of at most `width` bytes (a longer word stands alone), each
// line prefixed by `indent` and ended by a newline.
std::string wrapped(std::string_view text, std::string_view indent, std::size_t width) {
    std::string out, line;
    std::size_t start = 0;
    while (start < text.size()) {
        std::size_t end = text.find(' ', start);
        if (end == std::string_view::npos) end = text.size();
        const std::string_view word = text.substr(start, end - start);
        if (!line.empty() && line.size() + 1 + word.size() > width) {
            out.append(indent).append(line).append("\n");
            line.clear();
        }
        line.append(line.empty() ? "" : " ").append(word);
        start = end + 1;
    }
    if (!line.empty()) out.append(indent).append(line).append("\n");
    return out;
}

}  // namespace

std::vector<std::string_view> scene_key_sections() {
    std::vector<std::string_view> sections;
    for (const Parameter& p : parameter_table())
        if (std::find(sections.begin(), sections.end(), p.section) == sections.end()) sections.push_back(p.section);
    return sections;
}

std::string scene_keys_text() {
    std::string out =
        "Scene keys: every key a scene file may hold (docs/scene-format.md), with its type, unit, default,\n"
        "valid values and what a change takes: live (applies at the next step: the editor's sliders),\n"
        "re-cook (cooked into the fabric) or rebuild (read when the world is built from the scene).\n"
        "Keys of arrays of tables ([[cloth]], [[cloth.pin]], [[motion]], [[collider]]) are set per entry:\n"
        "--set cloth.flag.material.friction=0.5 or --set cloth.0.material.friction=0.5.\n";
    std::string_view section;
    for (const Parameter& p : parameter_table()) {
        if (p.section != section) {
            section = p.section;
            out.append("\n[").append(section).append("]\n");
        }
        std::string facts(type_name(p.type));
        if (!p.unit.empty()) facts.append(", ").append(p.unit);
        const std::string def = parameter_default_text(p);
        if (!def.empty()) facts.append("; default ").append(def);
        const std::string range = parameter_range_text(p);
        if (!range.empty()) facts.append("; ").append(range);
        if (p.shapes != 0) facts.append("; ").append(shapes_text(p)).append(" only");
        facts.append("; ").append(effect_name(p.effect));
        out.append("  ").append(p.key()).append("  (").append(facts).append(")\n");
        out.append(wrapped(p.doc, "      ", 94));
    }
    return out;
}

std::string scene_keys_begin(std::string_view section) {
    return "<!-- generated table: " + std::string(section) + " (weft help scene-keys --markdown) -->";
}

std::string scene_keys_markdown(std::string_view section) {
    const bool shapes = section == "collider";
    std::string out = shapes ? "| key | type | unit | default | range | shapes | meaning |\n|---|---|---|---|---|---|---|\n"
                             : "| key | type | unit | default | range | meaning |\n|---|---|---|---|---|---|\n";
    for (const Parameter& p : parameter_table()) {
        if (p.section != section) continue;
        const std::string type = p.type == ParameterType::Box ? "`" + std::string(type_name(p.type)) + "`"
                                                              : std::string(type_name(p.type));
        // Units are SI except orientations and the field of view, in degrees: the exception stands out.
        const std::string unit = p.unit == "degrees" ? "**degrees**" : std::string(p.unit);
        out.append("| `").append(p.name).append("` | ").append(type).append(" | ").append(cell(unit)).append(" | ");
        out.append(cell(code_quoted(parameter_default_text(p)))).append(" | ");
        out.append(code_quoted(parameter_range_text(p))).append(" | ");
        if (shapes) out.append(p.name == "shape" ? "" : shapes_text(p)).append(" | ");
        out.append(p.doc).append(" |\n");
    }
    return out;
}

std::string scene_keys_markdown() {
    std::string out;
    for (const std::string_view section : scene_key_sections())
        out.append(scene_keys_begin(section))
            .append("\n")
            .append(scene_keys_markdown(section))
            .append(kSceneKeysEnd)
            .append("\n\n");
    return out;
}

}  // namespace weft::cli
