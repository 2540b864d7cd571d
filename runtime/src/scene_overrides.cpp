// `--set key=value` overrides: parsed as a one-line TOML document and merged into the scene.
#include "scene_overrides.h"

#include <algorithm>
#include <cctype>
#include <string_view>

#include "scene_reader.h"
#include "weft/error.h"

namespace weft::scene_toml {
namespace {

std::string_view trim(std::string_view s) {
    const auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
    while (!s.empty() && space(s.front())) s.remove_prefix(1);
    while (!s.empty() && space(s.back())) s.remove_suffix(1);
    return s;
}

bool is_index(std::string_view s) {
    return !s.empty() && s.size() < 10 &&
           std::all_of(s.begin(), s.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; });
}

// A word that TOML would reject as a value but a shell user obviously meant as a string
// (`--set solver.precision=float`).
bool is_bare_word(std::string_view s) {
    if (s.empty() || s == "true" || s == "false" || s == "inf" || s == "nan") return false;
    if (std::isalpha(static_cast<unsigned char>(s.front())) == 0) return false;
    return std::all_of(s.begin(), s.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-';
    });
}

class Merger {
public:
    explicit Merger(std::string label) : label_(std::move(label)) {}

    void merge(toml::table& base, toml::table& over, const std::string& path) {
        for (auto&& [key, value] : over) {
            const std::string name(key.str());
            const std::string here = path.empty() ? name : path + "." + name;
            toml::node* existing = base.get(name);
            if (existing == nullptr) {
                if (const auto* t = value.as_table(); t != nullptr && !t->empty() &&
                                                      std::all_of(t->begin(), t->end(), [](auto&& kv) {
                                                          return is_index(kv.first.str());
                                                      }))
                    fail(here, "the scene has no '" + name + "' entries to select from");
                // A key the file omitted; whether the format knows it is checked by the validator.
                base.insert_or_assign(key, std::move(value));
            } else if (existing->is_table() && value.is_table()) {
                merge(*existing->as_table(), *value.as_table(), here);
            } else if (existing->is_array() && value.is_table()) {
                merge_into_array(*existing->as_array(), *value.as_table(), here);
            } else {
                base.insert_or_assign(key, std::move(value));
            }
        }
    }

private:
    // `cloth.0.x` or `cloth.flag.x`: select the entry, then merge into it.
    void merge_into_array(toml::array& base, toml::table& over, const std::string& path) {
        for (auto&& [key, value] : over) {
            const std::string selector(key.str());
            std::size_t index = base.size();
            if (is_index(selector)) {
                index = static_cast<std::size_t>(std::stoul(selector));
                if (index >= base.size())
                    fail(path + "." + selector, "index " + selector + " is out of range (the scene has " +
                                                    std::to_string(base.size()) + " '" + last_name(path) +
                                                    "' entries)");
            } else {
                std::vector<std::string> names;
                for (std::size_t i = 0; i < base.size(); ++i) {
                    const auto* t = base[i].as_table();
                    if (t == nullptr) continue;
                    if (const auto* n = t->get_as<std::string>("name")) {
                        names.push_back(n->get());
                        if (n->get() == selector && index == base.size()) index = i;
                    }
                }
                if (index == base.size()) {
                    const std::string guess = closest(selector, names);
                    std::string list;
                    for (const auto& n : names) list += (list.empty() ? "'" : ", '") + n + "'";
                    fail(path + "." + selector,
                         "no '" + last_name(path) + "' entry is named '" + selector + "'" +
                             (guess.empty() ? "" : " (did you mean '" + guess + "'?)") + " (expected an index" +
                             (list.empty() ? std::string() : " or one of " + list) + ")");
                }
            }
            const std::string here = path + "[" + std::to_string(index) + "]";
            toml::node& element = base[index];
            if (element.is_table() && value.is_table()) {
                merge(*element.as_table(), *value.as_table(), here);
            } else if (!element.is_table() && !value.is_table()) {
                base.replace(base.cbegin() + static_cast<std::ptrdiff_t>(index), std::move(value));
            } else {
                fail(here, "cannot replace a whole entry (expected a key inside it, e.g. " + path + "." + selector +
                               ".name=...)");
            }
        }
    }

    static std::string last_name(const std::string& path) {
        const auto dot = path.rfind('.');
        std::string name = dot == std::string::npos ? path : path.substr(dot + 1);
        const auto bracket = name.find('[');
        return bracket == std::string::npos ? name : name.substr(0, bracket);
    }

    [[noreturn]] void fail(const std::string& key, const std::string& what) const {
        throw Error(label_ + ": key '" + key + "': " + what);
    }

    std::string label_;
};

}  // namespace

void apply_overrides(toml::table& document, std::span<const std::string> overrides) {
    for (const std::string& text : overrides) {
        const std::string label = std::string(kOverridePrefix) + text + "'";
        const auto eq = text.find('=');
        if (eq == std::string::npos)
            throw Error(label + ": expected key=value, e.g. solver.substeps=4 or wind.velocity=[5,0,0]");
        const std::string_view key = trim(std::string_view(text).substr(0, eq));
        const std::string_view value = trim(std::string_view(text).substr(eq + 1));
        if (key.empty()) throw Error(label + ": the key before '=' is empty (expected e.g. solver.substeps=4)");
        if (value.empty()) throw Error(label + ": the value after '=' is empty (expected a TOML value, e.g. 4, 1e4, \"text\", [0, 1, 0])");
        std::string quoted;
        if (is_bare_word(value)) {
            quoted.reserve(value.size() + 2);
            quoted.push_back('"');
            quoted.append(value);
            quoted.push_back('"');
        } else {
            quoted.assign(value);
        }
        toml::table overlay;
        try {
            overlay = toml::parse(std::string(key) + " = " + quoted, label);
        } catch (const toml::parse_error& e) {
            throw Error(label + ": cannot parse as TOML: " + std::string(e.description()) +
                        " (expected key=value with a TOML value, e.g. 4, 1e4, \"text\", [0, 1, 0])");
        }
        Merger(label).merge(document, overlay, "");
    }
}

}  // namespace weft::scene_toml
