#include "json_writer.h"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <system_error>

namespace weft::json {

std::string json_string(std::string_view text) {
    std::string out;
    out.reserve(text.size() + 2);
    out += '"';
    for (const char c : text) {
        switch (c) {
            case '"':
                out += "\\\"";
                break;
            case '\\':
                out += "\\\\";
                break;
            case '\b':
                out += "\\b";
                break;
            case '\f':
                out += "\\f";
                break;
            case '\n':
                out += "\\n";
                break;
            case '\r':
                out += "\\r";
                break;
            case '\t':
                out += "\\t";
                break;
            default:
                if (static_cast<unsigned char>(c) < 0x20) {
                    static constexpr char kHex[] = "0123456789abcdef";
                    const auto u = static_cast<unsigned char>(c);
                    out += "\\u00";
                    out += kHex[u >> 4];
                    out += kHex[u & 0xF];
                } else {
                    out += c;
                }
        }
    }
    out += '"';
    return out;
}

std::string json_number(double value) {
    if (!std::isfinite(value)) return "null";
    char buf[64];
    const auto [end, ec] = std::to_chars(buf, buf + sizeof(buf), value);
    if (ec != std::errc{}) return "null";  // cannot happen with 64 bytes; stay valid JSON regardless
    return {buf, end};
}

void JsonWriter::newline() {
    out_ << '\n';
    for (std::size_t i = 0; i < stack_.size() * static_cast<std::size_t>(indent_); ++i) out_ << ' ';
}

void JsonWriter::before_value() {
    if (stack_.empty()) {
        if (wrote_root_) throw std::logic_error("JsonWriter: a second top-level value");
        wrote_root_ = true;
        return;
    }
    Level& level = stack_.back();
    if (level.object) {
        if (!after_key_) throw std::logic_error("JsonWriter: value in an object without a key");
        after_key_ = false;
        return;
    }
    if (level.count++ > 0) out_ << (level.compact ? ", " : ",");
    if (!level.compact) newline();
}

JsonWriter& JsonWriter::key(std::string_view name) {
    if (stack_.empty() || !stack_.back().object) throw std::logic_error("JsonWriter: key outside an object");
    if (after_key_) throw std::logic_error("JsonWriter: two keys in a row");
    Level& level = stack_.back();
    if (level.count++ > 0) out_ << ',';
    newline();
    out_ << json_string(name) << ": ";
    after_key_ = true;
    return *this;
}

JsonWriter& JsonWriter::begin_object() {
    before_value();
    out_ << '{';
    stack_.push_back({.object = true});
    return *this;
}

JsonWriter& JsonWriter::begin_array(bool compact) {
    before_value();
    out_ << '[';
    stack_.push_back({.object = false, .compact = compact});
    return *this;
}

JsonWriter& JsonWriter::close(bool object) {
    if (stack_.empty() || stack_.back().object != object || after_key_) {
        throw std::logic_error(object ? "JsonWriter: end_object without a matching begin_object"
                                      : "JsonWriter: end_array without a matching begin_array");
    }
    const Level level = stack_.back();
    stack_.pop_back();
    if (level.count > 0 && !level.compact) newline();
    out_ << (object ? '}' : ']');
    if (stack_.empty()) out_ << '\n';
    return *this;
}

JsonWriter& JsonWriter::end_object() { return close(true); }
JsonWriter& JsonWriter::end_array() { return close(false); }

JsonWriter& JsonWriter::value(std::string_view text) {
    before_value();
    out_ << json_string(text);
    return *this;
}

JsonWriter& JsonWriter::value(bool flag) {
    before_value();
    out_ << (flag ? "true" : "false");
    return *this;
}

JsonWriter& JsonWriter::value(double number) {
    before_value();
    out_ << json_number(number);
    return *this;
}

JsonWriter& JsonWriter::integer(std::int64_t number) {
    before_value();
    out_ << number;
    return *this;
}

JsonWriter& JsonWriter::unsigned_integer(std::uint64_t number) {
    before_value();
    out_ << number;
    return *this;
}

JsonWriter& JsonWriter::null() {
    before_value();
    out_ << "null";
    return *this;
}

}  // namespace weft::json
