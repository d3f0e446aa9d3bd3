#pragma once
// Command-line helpers shared by the bench tools (each keeps its own usage text).
#include <cmath>
#include <cstdlib>
#include <string>

namespace hopper::bench {

using Usage = void (*)(const std::string& why);

// The number `text` given for option `opt`, within [lo, hi]; otherwise `usage` (which exits)
// names the option, the text and the range.
inline double number(const std::string& opt, const char* text, double lo, double hi, Usage usage) {
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (end == text || *end != '\0' || !std::isfinite(v) || v < lo || v > hi) {
        usage(opt + " '" + text + "': expected a number in [" + std::to_string(lo) + ", " +
              std::to_string(hi) + "]");
        std::exit(2);
    }
    return v;
}

}  // namespace hopper::bench
