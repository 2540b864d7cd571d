#pragma once
// Reading validated values out of a parsed TOML table. Every accessor checks the type and the valid
// range of one key and, when something is wrong, throws `weft::Error` as
//   FILE:LINE:COLUMN: key 'cloth[0].material.stretch_stiffness': <what is wrong> (expected ...)
// or, for a value that came from a `--set` override,
//   --set 'key=value': key '...': <what is wrong> (expected ...)
// Accessors also register the key as known, so that `finish()` reports every other key of the table
// as unknown, with a "did you mean" suggestion when one is close.

#include <toml++/toml.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "weft/parameters.h"
#include "weft/types.h"

namespace weft::scene_toml {

/// Source label that marks nodes parsed from a `--set` override (see scene_overrides.cpp).
inline constexpr std::string_view kOverridePrefix = "--set '";

/// "FILE:LINE:COLUMN: " for a node of the scene file, "--set 'k=v': " for a node of an override,
/// "FILE: " when the node has no source position.
[[nodiscard]] std::string location(const toml::source_region& where, std::string_view file);

/// The candidate closest to `word` (case-insensitive edit distance) when it is close enough to be a
/// likely typo; empty otherwise.
[[nodiscard]] std::string closest(std::string_view word, std::span<const std::string> candidates);

/// Number formatting for messages: shortest of %g with the exponent tidied ("1e8", "0.49", "1e-5").
[[nodiscard]] std::string format_number(double value);

/// Short description of a node for "got …" in messages: `the string "four"`, `4.5`, `an array`.
[[nodiscard]] std::string describe(const toml::node& node);

/// A closed, open or half-open interval of valid values (the parameter table's).
using Range = ParameterRange;

/// One TOML table being validated. `path` is the table's key path as shown in messages
/// ("cloth[0].material"); `file` is the scene's display name.
class Table {
public:
    Table(const toml::table& table, std::string path, std::string file);

    [[nodiscard]] const std::string& path() const { return path_; }
    [[nodiscard]] const std::string& file() const { return file_; }
    [[nodiscard]] const toml::table& raw() const { return *table_; }
    [[nodiscard]] std::string key_path(std::string_view key) const;

    /// The node under `key` or null; registers `key` as known.
    [[nodiscard]] const toml::node* find(std::string_view key);
    [[nodiscard]] bool has(std::string_view key) { return find(key) != nullptr; }

    [[nodiscard]] double number(std::string_view key, double fallback, Range range);
    [[nodiscard]] std::optional<double> optional_number(std::string_view key, Range range);
    [[nodiscard]] int integer(std::string_view key, int fallback, std::int64_t lo, std::int64_t hi);
    [[nodiscard]] bool boolean(std::string_view key, bool fallback);
    /// A non-empty string.
    [[nodiscard]] std::optional<std::string> optional_string(std::string_view key);
    [[nodiscard]] std::string required_string(std::string_view key, std::string_view expected);
    /// A string that must be one of `choices`; returns its index.
    [[nodiscard]] std::optional<std::size_t> choice(std::string_view key, std::span<const std::string_view> choices);
    /// An array of three finite numbers.
    [[nodiscard]] Vec3d vec3(std::string_view key, Vec3d fallback);
    [[nodiscard]] std::optional<Vec3d> optional_vec3(std::string_view key);
    /// A sub-table (a `[section]` or an inline `{ … }` table); nullopt when absent.
    [[nodiscard]] std::optional<Table> table(std::string_view key);
    /// An array of tables (`[[section]]` or `[{…}, {…}]`); empty when absent.
    [[nodiscard]] std::vector<Table> array_of_tables(std::string_view key);

    /// Registers `key` and throws if it is present: "<reason>".
    void reject(std::string_view key, std::string_view reason);
    /// Throws for the first key of the table that no accessor asked for.
    void finish() const;

    [[noreturn]] void fail(std::string_view key, const toml::node* at, std::string_view what) const;
    /// Error located at the table itself (e.g. a missing required key).
    [[noreturn]] void fail_here(std::string_view key, std::string_view what) const;

private:
    [[noreturn]] void fail_type(std::string_view key, const toml::node& at, std::string_view expected) const;
    const toml::table* table_;
    std::string path_;
    std::string file_;
    std::vector<std::string> known_;
};

}  // namespace weft::scene_toml
