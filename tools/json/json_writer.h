#pragma once
/// @file
/// A small streaming JSON writer for the files the `weft` tool and the benchmarks (bench/) write
/// (stats, bench results): correct string escaping, shortest round-trip numbers, and `null` for NaN
/// and infinities (JSON has no spelling for them).

#include <concepts>
#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace weft::json {

/// `text` as a JSON string literal, quotes included. Control characters become escapes; other bytes
/// (UTF-8) pass through unchanged.
[[nodiscard]] std::string json_string(std::string_view text);
/// `value` as a JSON number in its shortest round-trip form, or `null` when it is not finite.
[[nodiscard]] std::string json_number(double value);

/// Writes one JSON document to a stream, pretty-printed. Misuse (a value where a key is due, closing
/// the wrong bracket) throws std::logic_error: it is a bug in the caller, not bad input.
class JsonWriter {
public:
    explicit JsonWriter(std::ostream& out, int indent = 2) : out_(out), indent_(indent) {}

    JsonWriter& begin_object();
    JsonWriter& end_object();
    /// `compact` puts all elements on one line (per-frame series stay readable that way).
    JsonWriter& begin_array(bool compact = false);
    JsonWriter& end_array();
    JsonWriter& key(std::string_view name);

    JsonWriter& value(std::string_view text);
    JsonWriter& value(const char* text) { return value(std::string_view(text)); }
    JsonWriter& value(bool flag);
    JsonWriter& value(double number);
    JsonWriter& value(float number) { return value(static_cast<double>(number)); }
    template <std::integral I>
    requires(!std::same_as<I, bool>) JsonWriter& value(I number) {
        if constexpr (std::is_signed_v<I>)
            return integer(static_cast<std::int64_t>(number));
        else
            return unsigned_integer(static_cast<std::uint64_t>(number));
    }
    JsonWriter& null();

    /// key(name) followed by value(v).
    template <typename T>
    JsonWriter& field(std::string_view name, const T& v) {
        key(name);
        return value(v);
    }

    /// True once the top-level value is complete.
    [[nodiscard]] bool done() const { return stack_.empty() && wrote_root_; }

private:
    struct Level {
        bool object = false;
        bool compact = false;
        int count = 0;
    };
    JsonWriter& integer(std::int64_t number);
    JsonWriter& unsigned_integer(std::uint64_t number);
    void before_value();
    void newline();
    JsonWriter& close(bool object);

    std::ostream& out_;
    int indent_;
    std::vector<Level> stack_;
    bool after_key_ = false;
    bool wrote_root_ = false;
};

}  // namespace weft::json
