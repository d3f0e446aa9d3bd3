#include "cli/json_writer.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace hopper::cli {

namespace {

// Length of the well-formed UTF-8 sequence starting at s[i], or 0 if it is not well formed
// (Unicode 15, table 3-7: no overlong forms, no surrogates, nothing above U+10FFFF).
std::size_t utf8_sequence_length(std::string_view s, std::size_t i) {
    const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
    const auto in = [](unsigned char b, unsigned lo, unsigned hi) { return b >= lo && b <= hi; };
    const unsigned char b0 = byte(i);
    std::size_t n = 0;
    unsigned lo1 = 0x80, hi1 = 0xBF;  // allowed range of the second byte
    if (b0 < 0x80) return 1;
    if (in(b0, 0xC2, 0xDF)) {
        n = 2;
    } else if (in(b0, 0xE0, 0xEF)) {
        n = 3;
        if (b0 == 0xE0) lo1 = 0xA0;
        if (b0 == 0xED) hi1 = 0x9F;
    } else if (in(b0, 0xF0, 0xF4)) {
        n = 4;
        if (b0 == 0xF0) lo1 = 0x90;
        if (b0 == 0xF4) hi1 = 0x8F;
    } else {
        return 0;
    }
    if (i + n > s.size()) return 0;
    if (!in(byte(i + 1), lo1, hi1)) return 0;
    for (std::size_t k = 2; k < n; ++k)
        if (!in(byte(i + k), 0x80, 0xBF)) return 0;
    return n;
}

}  // namespace

std::string json_quote(std::string_view s) {
    static constexpr char hex[] = "0123456789abcdef";
    std::string out;
    out.reserve(s.size() + 2);
    out += '"';
    for (std::size_t i = 0; i < s.size();) {
        const auto c = static_cast<unsigned char>(s[i]);
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
                if (c < 0x20) {
                    out += "\\u00";
                    out += hex[c >> 4];
                    out += hex[c & 0xF];
                } else if (c >= 0x80) {
                    const std::size_t n = utf8_sequence_length(s, i);
                    if (n == 0) {
                        out += "\\ufffd";  // replacement character for an invalid byte
                        ++i;
                    } else {
                        out.append(s.substr(i, n));
                        i += n;
                    }
                    continue;
                } else {
                    out += static_cast<char>(c);
                }
        }
        ++i;
    }
    out += '"';
    return out;
}

std::string json_number(double v) {
    if (!std::isfinite(v)) return "null";
    std::array<char, 32> buf{};
    const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), v);
    if (res.ec != std::errc{}) throw std::logic_error("json_number: to_chars failed");
    return std::string(buf.data(), res.ptr);
}

JsonWriter& JsonWriter::key(std::string_view k) {
    if (stack_.empty() || !stack_.back().object)
        throw std::logic_error("JsonWriter: key \"" + std::string(k) + "\" outside an object");
    Frame& f = stack_.back();
    if (f.have_key) throw std::logic_error("JsonWriter: two keys in a row");
    if (f.count > 0) out_ += ',';
    if (f.inline_) {
        if (f.count > 0) out_ += ' ';
    } else {
        newline(stack_.size());
    }
    out_ += json_quote(k);
    out_ += ": ";
    f.have_key = true;
    return *this;
}

void JsonWriter::before_value() {
    if (done_) throw std::logic_error("JsonWriter: a second top-level value");
    if (stack_.empty()) return;
    Frame& f = stack_.back();
    if (f.object) {
        if (!f.have_key) throw std::logic_error("JsonWriter: value in an object without a key");
        f.have_key = false;
    } else {
        if (f.count > 0) out_ += ',';
        if (f.inline_) {
            if (f.count > 0) out_ += ' ';
        } else {
            newline(stack_.size());
        }
    }
    ++f.count;
}

void JsonWriter::newline(std::size_t depth) {
    out_ += '\n';
    out_.append(depth * static_cast<std::size_t>(indent_), ' ');
}

JsonWriter& JsonWriter::open(char bracket, bool inline_) {
    before_value();
    const bool parent_inline = !stack_.empty() && stack_.back().inline_;
    stack_.push_back(Frame{bracket == '{', inline_ || parent_inline});
    out_ += bracket;
    return *this;
}

JsonWriter& JsonWriter::close(char bracket) {
    const bool object = bracket == '}';
    if (stack_.empty() || stack_.back().object != object)
        throw std::logic_error(std::string("JsonWriter: unbalanced '") + bracket + "'");
    const Frame f = stack_.back();
    if (f.have_key) throw std::logic_error("JsonWriter: key without a value");
    stack_.pop_back();
    if (!f.inline_ && f.count > 0) newline(stack_.size());
    out_ += bracket;
    if (stack_.empty()) done_ = true;
    return *this;
}

JsonWriter& JsonWriter::scalar(const std::string& text) {
    before_value();
    out_ += text;
    if (stack_.empty()) done_ = true;
    return *this;
}

JsonWriter& JsonWriter::null() {
    return scalar("null");
}

JsonWriter& JsonWriter::value(bool b) {
    return scalar(b ? "true" : "false");
}

JsonWriter& JsonWriter::value(double v) {
    if (!std::isfinite(v)) ++nonfinite_;
    return scalar(json_number(v));
}

FieldsSummary summarize_fields(const engine::FieldMoments& m) {
    FieldsSummary s;
    const auto& speed = m.mean[static_cast<int>(engine::Field::speed)];
    const auto& pressure = m.mean[static_cast<int>(engine::Field::pressure)];
    const std::size_t n = std::min({m.windows.size(), speed.size(), pressure.size()});
    for (std::size_t c = 0; c < n; ++c) {
        if (m.windows[c] <= 0) continue;
        s.max_mean_speed = s.cells_with_data == 0 ? speed[c] : std::max(s.max_mean_speed, speed[c]);
        s.max_mean_pressure =
            s.cells_with_data == 0 ? pressure[c] : std::max(s.max_mean_pressure, pressure[c]);
        ++s.cells_with_data;
    }
    return s;
}

void write_fields_summary(JsonWriter& w, const engine::FieldMoments& m) {
    const engine::FieldGrid& g = m.grid;
    w.field("kernel", engine::to_string(g.kernel));
    if (g.kernel == engine::FieldKernel::gaussian) w.field("kernel_width_m", g.kernel_width);
    w.field("cell_m", g.cell).field("x0_m", g.x0).field("y0_m", g.y0);
    w.field("nx", g.nx).field("ny", g.ny);
    w.field("samples", m.samples).field("total_windows", m.total_windows);
    w.field("t_first", m.t_first).field("t_last", m.t_last);
    const FieldsSummary s = summarize_fields(m);
    w.field("cells_with_data", s.cells_with_data);
    w.field("max_mean_speed", s.max_mean_speed);
    w.field("max_mean_pressure", s.max_mean_pressure);
}

}  // namespace hopper::cli
