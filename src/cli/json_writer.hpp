#pragma once
// A small streaming JSON writer for the command line's machine-readable output.
//
// Layout: containers opened with begin_object()/begin_array() put each member on its own line,
// indented; containers opened with the *_inline variants (and everything nested in them) stay on
// one line. So a result prints one key per line with number arrays on that same line, which keeps
// diffs readable and lets a test drop the wall-clock lines by key.
//
// Numbers: doubles are written in the shortest form that reads back to the same bits
// (std::to_chars), so output is deterministic and round-trips exactly. JSON has no NaN or
// infinity: a non-finite double is written as null and counted (nonfinite_count()), so a caller
// or a test can treat it as the bug it is. Strings: quotes, backslashes and control characters are
// escaped; valid UTF-8 passes through unchanged; each byte of an invalid UTF-8 sequence becomes
// U+FFFD, so the output is always valid JSON.
//
// Misuse (a value in an object without a key, a key in an array, unbalanced ends, a second
// top-level value) throws std::logic_error: it is a programming error, not bad input.

#include <concepts>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hopper/engine/fields.hpp"

namespace hopper::cli {

// `s` as a JSON string literal, quotes included.
std::string json_quote(std::string_view s);

// `v` as a JSON number (shortest round-trip form), or "null" when v is not finite.
std::string json_number(double v);

class JsonWriter {
  public:
    explicit JsonWriter(int indent = 2) : indent_(indent) {}

    JsonWriter& begin_object() { return open('{', false); }
    JsonWriter& begin_array() { return open('[', false); }
    JsonWriter& begin_object_inline() { return open('{', true); }
    JsonWriter& begin_array_inline() { return open('[', true); }
    JsonWriter& end_object() { return close('}'); }
    JsonWriter& end_array() { return close(']'); }

    // The next value belongs to this key (only inside an object).
    JsonWriter& key(std::string_view k);

    JsonWriter& null();
    JsonWriter& value(bool b);
    JsonWriter& value(double v);
    template <std::integral T>
    requires(!std::same_as<T, bool>) JsonWriter& value(T v) { return scalar(std::to_string(v)); }
    JsonWriter& value(std::string_view s) { return scalar(json_quote(s)); }
    JsonWriter& value(const char* s) { return value(std::string_view(s)); }
    JsonWriter& value(const std::string& s) { return value(std::string_view(s)); }
    template <class T>
    JsonWriter& value(const std::optional<T>& v) {
        return v ? value(*v) : null();
    }

    // A whole range as one inline array (elements written with value()).
    template <class Range>
    JsonWriter& array_inline(const Range& r) {
        begin_array_inline();
        for (const auto& x : r)
            value(static_cast<ElementOf<Range>>(x));
        return end_array();
    }

    // key(k).value(v) / key(k).array_inline(r).
    template <class T>
    JsonWriter& field(std::string_view k, const T& v) {
        key(k);
        return value(v);
    }
    template <class Range>
    JsonWriter& field_array(std::string_view k, const Range& r) {
        key(k);
        return array_inline(r);
    }

    // True once one complete top-level value has been written.
    bool complete() const { return done_; }
    // The text written so far (without a trailing newline).
    const std::string& str() const { return out_; }
    // How many non-finite doubles were written as null.
    int nonfinite_count() const { return nonfinite_; }

  private:
    // The element type of a range, with std::vector<bool>'s proxy read as bool.
    template <class Range>
    using ElementOf = std::conditional_t<std::is_same_v<Range, std::vector<bool>>, bool,
                                         typename Range::value_type>;

    struct Frame {
        bool object;
        bool inline_;
        int count = 0;
        bool have_key = false;
    };

    JsonWriter& open(char bracket, bool inline_);
    JsonWriter& close(char bracket);
    JsonWriter& scalar(const std::string& text);
    void before_value();  // separator and indentation before a value (or a key)
    void newline(std::size_t depth);

    int indent_;
    std::string out_;
    std::vector<Frame> stack_;
    bool done_ = false;
    int nonfinite_ = 0;
};

// What the compact summaries of coarse-grained fields report (`campaign simulate --json`,
// `campaign analyze`): the nodes with at least one window, and the largest mean speed (m/s) and
// mean pressure (m g) over them (0 when there are none).
struct FieldsSummary {
    std::int64_t cells_with_data = 0;
    double max_mean_speed = 0.0;
    double max_mean_pressure = 0.0;
};
FieldsSummary summarize_fields(const engine::FieldMoments& m);

// The compact summary of fields as members of the open object (no per-node arrays):
// kernel, kernel_width_m (Gaussian only), cell_m, x0_m, y0_m, nx, ny, samples, total_windows,
// t_first, t_last, cells_with_data, max_mean_speed, max_mean_pressure.
void write_fields_summary(JsonWriter& w, const engine::FieldMoments& m);

}  // namespace hopper::cli
