#include "cli/options.hpp"

#include <charconv>
#include <cmath>
#include <string>
#include <system_error>

#include "hopper/core/error.hpp"

namespace hopper::cli {

namespace {

[[noreturn]] void reject(std::string_view option, std::string_view what, std::string_view text) {
    throw core::ConfigError(std::string(option) + " must be " + std::string(what) + ", got '" +
                            std::string(text) + "'");
}

}  // namespace

std::uint64_t parse_seed(std::string_view option, std::string_view text) {
    constexpr std::string_view what = "a non-negative integer";
    // from_chars accepts no sign, no spaces and no prefix: digits only.
    if (text.empty() || text.front() < '0' || text.front() > '9') reject(option, what, text);
    std::uint64_t v = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec == std::errc::result_out_of_range)
        reject(option, "a non-negative integer of at most 18446744073709551615", text);
    if (ec != std::errc{} || end != text.data() + text.size()) reject(option, what, text);
    return v;
}

std::uint64_t parse_seed_text(std::string_view option, std::string_view text) {
    std::string_view digits = text;
    if (digits.size() > 1 && digits.front() == 's' && digits[1] >= '0' && digits[1] <= '9')
        digits.remove_prefix(1);
    try {
        return parse_seed(option, digits);
    } catch (const core::ConfigError& e) {
        if (std::string_view(e.what()).find("at most") != std::string_view::npos)
            reject(option, "a non-negative integer of at most 18446744073709551615", text);
        reject(option, "a non-negative integer (or a seed_str: 's' and its digits)", text);
    }
}

double parse_finite(std::string_view option, std::string_view text) {
    constexpr std::string_view what = "a finite number";
    std::string_view digits = text;
    if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
    if (digits.empty() || digits.front() == '+') reject(option, what, text);
    double v = 0.0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v,
                                           std::chars_format::general);
    if (ec != std::errc{} || end != digits.data() + digits.size() || !std::isfinite(v))
        reject(option, what, text);
    return v;
}

}  // namespace hopper::cli
