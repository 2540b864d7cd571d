// Validated access to parsed TOML tables (see scene_reader.h for the error format).
#include "scene_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>

#include "weft/error.h"

namespace weft::scene_toml {

std::string location(const toml::source_region& where, std::string_view file) {
    if (where.path && where.path->rfind(kOverridePrefix, 0) == 0) return *where.path + ": ";
    const std::string name = where.path && !where.path->empty() ? *where.path : std::string(file);
    if (where.begin.line == 0) return name + ": ";
    return name + ":" + std::to_string(where.begin.line) + ":" + std::to_string(where.begin.column) + ": ";
}

namespace {

// Optimal-string-alignment distance (Levenshtein plus adjacent transpositions), case-insensitive:
// "stifness" → "stiffness" and "substpes" → "substeps" are both one edit.
std::size_t edit_distance(std::string_view a, std::string_view b) {
    const auto lower = [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); };
    const std::size_t n = a.size(), m = b.size();
    std::vector<std::size_t> d((n + 1) * (m + 1));
    const auto at = [&](std::size_t i, std::size_t j) -> std::size_t& { return d[i * (m + 1) + j]; };
    for (std::size_t i = 0; i <= n; ++i) at(i, 0) = i;
    for (std::size_t j = 0; j <= m; ++j) at(0, j) = j;
    for (std::size_t i = 1; i <= n; ++i) {
        for (std::size_t j = 1; j <= m; ++j) {
            const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
            at(i, j) = std::min({at(i - 1, j) + 1, at(i, j - 1) + 1, at(i - 1, j - 1) + cost});
            if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1]))
                at(i, j) = std::min(at(i, j), at(i - 2, j - 2) + 1);
        }
    }
    return at(n, m);
}

std::string join_quoted(std::span<const std::string> words) {
    std::string out;
    for (std::size_t i = 0; i < words.size(); ++i) {
        if (i > 0) out += ", ";
        out += "'" + words[i] + "'";
    }
    return out;
}

}  // namespace

std::string closest(std::string_view word, std::span<const std::string> candidates) {
    // Allow roughly one typo per three characters, at most three.
    const std::size_t limit = std::clamp<std::size_t>(word.size() / 3, 1, 3);
    std::string best;
    std::size_t best_distance = limit + 1;
    for (const std::string& c : candidates) {
        const std::size_t d = edit_distance(word, c);
        if (d < best_distance) {
            best_distance = d;
            best = c;
        }
    }
    return best;
}

std::string format_number(double value) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.6g", value);
    std::string s = buffer;
    // %g writes 1e+08 and 1e-05; show 1e8 and 1e-5 as people write them in scene files.
    const auto e = s.find('e');
    if (e != std::string::npos) {
        std::string mantissa = s.substr(0, e);
        std::string exponent = s.substr(e + 1);
        bool negative = false;
        if (!exponent.empty() && (exponent[0] == '+' || exponent[0] == '-')) {
            negative = exponent[0] == '-';
            exponent.erase(0, 1);
        }
        exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
        s = mantissa + "e" + (negative ? "-" : "") + exponent;
    }
    return s;
}

std::string describe(const toml::node& node) {
    switch (node.type()) {
        case toml::node_type::string: return "the string \"" + std::string(node.as_string()->get()) + "\"";
        case toml::node_type::integer: return "the integer " + std::to_string(node.as_integer()->get());
        case toml::node_type::floating_point: return "the number " + format_number(node.as_floating_point()->get());
        case toml::node_type::boolean: return node.as_boolean()->get() ? "true" : "false";
        case toml::node_type::array: return "an array";
        case toml::node_type::table: return "a table";
        case toml::node_type::date: return "a date";
        case toml::node_type::time: return "a time";
        case toml::node_type::date_time: return "a date-time";
        case toml::node_type::none: break;
    }
    return "nothing";
}

Table::Table(const toml::table& table, std::string path, std::string file)
    : table_(&table), path_(std::move(path)), file_(std::move(file)) {}

std::string Table::key_path(std::string_view key) const {
    return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

const toml::node* Table::find(std::string_view key) {
    if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.emplace_back(key);
    return table_->get(key);
}

void Table::fail(std::string_view key, const toml::node* at, std::string_view what) const {
    const toml::source_region& where = at != nullptr ? at->source() : table_->source();
    throw Error(location(where, file_) + "key '" + key_path(key) + "': " + std::string(what));
}

void Table::fail_here(std::string_view key, std::string_view what) const { fail(key, nullptr, what); }

void Table::fail_type(std::string_view key, const toml::node& at, std::string_view expected) const {
    fail(key, &at, "wrong type: got " + describe(at) + " (expected " + std::string(expected) + ")");
}

std::optional<double> Table::optional_number(std::string_view key, Range range) {
    const toml::node* n = find(key);
    if (n == nullptr) return std::nullopt;
    const std::string expected = "a number in " + range.text();
    double v = 0.0;
    if (const auto* i = n->as_integer()) {
        v = static_cast<double>(i->get());
    } else if (const auto* f = n->as_floating_point()) {
        v = f->get();
    } else {
        fail_type(key, *n, expected);
    }
    if (!std::isfinite(v)) fail(key, n, "value " + format_number(v) + " is not finite (expected " + expected + ")");
    if (!range.contains(v)) fail(key, n, "value " + format_number(v) + " is out of range (expected " + expected + ")");
    return v;
}

double Table::number(std::string_view key, double fallback, Range range) {
    return optional_number(key, range).value_or(fallback);
}

int Table::integer(std::string_view key, int fallback, std::int64_t lo, std::int64_t hi) {
    const toml::node* n = find(key);
    if (n == nullptr) return fallback;
    const std::string expected = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    const auto* i = n->as_integer();
    if (i == nullptr) fail_type(key, *n, expected);
    const std::int64_t v = i->get();
    if (v < lo || v > hi) fail(key, n, "value " + std::to_string(v) + " is out of range (expected " + expected + ")");
    return static_cast<int>(v);
}

bool Table::boolean(std::string_view key, bool fallback) {
    const toml::node* n = find(key);
    if (n == nullptr) return fallback;
    const auto* b = n->as_boolean();
    if (b == nullptr) fail_type(key, *n, "true or false");
    return b->get();
}

std::optional<std::string> Table::optional_string(std::string_view key) {
    const toml::node* n = find(key);
    if (n == nullptr) return std::nullopt;
    const auto* s = n->as_string();
    if (s == nullptr) fail_type(key, *n, "a string");
    if (s->get().empty()) fail(key, n, "empty string (expected a non-empty string)");
    return s->get();
}

std::string Table::required_string(std::string_view key, std::string_view expected) {
    auto s = optional_string(key);
    if (!s) fail_here(key, "missing required key (expected " + std::string(expected) + ")");
    return *s;
}

std::optional<std::size_t> Table::choice(std::string_view key, std::span<const std::string_view> choices) {
    const toml::node* n = find(key);
    if (n == nullptr) return std::nullopt;
    std::vector<std::string> names(choices.begin(), choices.end());
    std::string expected = "one of ";
    for (std::size_t i = 0; i < names.size(); ++i) expected += (i > 0 ? ", \"" : "\"") + names[i] + "\"";
    const auto* s = n->as_string();
    if (s == nullptr) fail_type(key, *n, expected);
    for (std::size_t i = 0; i < names.size(); ++i)
        if (s->get() == names[i]) return i;
    const std::string guess = closest(s->get(), names);
    fail(key, n,
         "unknown value \"" + s->get() + "\"" + (guess.empty() ? "" : " (did you mean \"" + guess + "\"?)") +
             " (expected " + expected + ")");
}

std::optional<Vec3d> Table::optional_vec3(std::string_view key) {
    const toml::node* n = find(key);
    if (n == nullptr) return std::nullopt;
    constexpr std::string_view expected = "an array of 3 numbers, e.g. [0, 1, 0]";
    const auto* a = n->as_array();
    if (a == nullptr) fail_type(key, *n, expected);
    if (a->size() != 3)
        fail(key, n, "array has " + std::to_string(a->size()) + " elements (expected " + std::string(expected) + ")");
    Vec3d v{};
    for (int k = 0; k < 3; ++k) {
        const toml::node& e = (*a)[static_cast<std::size_t>(k)];
        if (const auto* i = e.as_integer()) {
            v[k] = static_cast<double>(i->get());
        } else if (const auto* f = e.as_floating_point()) {
            v[k] = f->get();
        } else {
            fail(key, &e,
                 "element " + std::to_string(k) + " is " + describe(e) + " (expected " + std::string(expected) + ")");
        }
        if (!std::isfinite(v[k]))
            fail(key, &e, "element " + std::to_string(k) + " is not finite (expected " + std::string(expected) + ")");
    }
    return v;
}

Vec3d Table::vec3(std::string_view key, Vec3d fallback) { return optional_vec3(key).value_or(fallback); }

std::optional<Table> Table::table(std::string_view key) {
    const toml::node* n = find(key);
    if (n == nullptr) return std::nullopt;
    const auto* t = n->as_table();
    if (t == nullptr) fail_type(key, *n, "a table");
    return Table(*t, key_path(key), file_);
}

std::vector<Table> Table::array_of_tables(std::string_view key) {
    std::vector<Table> out;
    const toml::node* n = find(key);
    if (n == nullptr) return out;
    const std::string expected = "an array of tables: [[" + key_path(key) + "]] sections";
    const auto* a = n->as_array();
    if (a == nullptr) fail_type(key, *n, expected);
    for (std::size_t i = 0; i < a->size(); ++i) {
        const toml::node& e = (*a)[i];
        const auto* t = e.as_table();
        if (t == nullptr)
            fail(key, &e, "element " + std::to_string(i) + " is " + describe(e) + " (expected " + expected + ")");
        out.emplace_back(*t, key_path(key) + "[" + std::to_string(i) + "]", file_);
    }
    return out;
}

void Table::reject(std::string_view key, std::string_view reason) {
    if (const toml::node* n = find(key)) fail(key, n, reason);
}

void Table::finish() const {
    for (auto&& [key, value] : *table_) {
        const std::string_view name = key.str();
        if (std::find(known_.begin(), known_.end(), name) != known_.end()) continue;
        const std::string guess = closest(name, known_);
        std::string what = "unknown key";
        if (!guess.empty()) {
            what += " (did you mean '" + guess + "'?)";
        } else {
            std::vector<std::string> sorted = known_;
            std::sort(sorted.begin(), sorted.end());
            what += " (expected one of " + join_quoted(sorted) + ")";
        }
        // Point at the key itself; keys inserted by an override carry the override's label.
        const toml::source_region& where = key.source().begin.line != 0 || key.source().path ? key.source() : value.source();
        throw Error(location(where, file_) + "key '" + key_path(name) + "': " + what);
    }
}

}  // namespace weft::scene_toml
