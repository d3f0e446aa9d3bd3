#include "cli/options.hpp"

#include <gtest/gtest.h>

#include <string>

#include "hopper/core/error.hpp"

namespace hopper::cli {
namespace {

// The message of the ConfigError thrown by f, or "" when nothing is thrown.
template <class F>
std::string error_of(F f) {
    try {
        f();
    } catch (const core::ConfigError& e) {
        return e.what();
    }
    return "";
}

TEST(ParseSeed, AcceptsNonNegativeIntegers) {
    EXPECT_EQ(parse_seed("--seed", "0"), 0u);
    EXPECT_EQ(parse_seed("--seed", "42"), 42u);
    EXPECT_EQ(parse_seed("--seed", "18446744073709551615"), 18446744073709551615ull);
}

TEST(ParseSeed, RejectsEverythingElseNamingOptionAndText) {
    for (const char* bad : {"-1", "abc", "1.5", "", " 1", "1 ", "+1", "1e3", "0x10", "12abc"}) {
        const std::string msg = error_of([&] { parse_seed("--seed", bad); });
        EXPECT_NE(msg.find("--seed must be a non-negative integer"), std::string::npos) << bad;
        std::string quoted = "'";  // (built by appending: GCC 12 warns falsely on "'" + string)
        quoted.append(bad).append("'");
        EXPECT_NE(msg.find(quoted), std::string::npos) << msg;
    }
    const std::string msg = error_of([] { parse_seed("--seed", "18446744073709551616"); });
    EXPECT_NE(msg.find("at most 18446744073709551615"), std::string::npos) << msg;
}

TEST(ParseSeedText, AcceptsTheStoresSeedStrAsWellAsDigits) {
    // the store's seed_str column ('s' and the digits) pasted back into --seed (issue 43, item 7)
    EXPECT_EQ(parse_seed_text("--seed", "s17273910456787253617"), 17273910456787253617ull);
    EXPECT_EQ(parse_seed_text("--seed", "42"), 42u);
    EXPECT_EQ(parse_seed_text("--seed", "s0"), 0u);
    for (const char* bad : {"s", "ss1", "s-1", "S12", "s1.5", "s 1", "1s"}) {
        const std::string msg = error_of([&] { parse_seed_text("--seed", bad); });
        EXPECT_NE(msg.find("--seed must be a non-negative integer"), std::string::npos) << bad;
        EXPECT_NE(msg.find("seed_str"), std::string::npos) << msg;
    }
}

TEST(ParseFinite, AcceptsDecimalNumbers) {
    EXPECT_DOUBLE_EQ(parse_finite("--D", "3"), 3.0);
    EXPECT_DOUBLE_EQ(parse_finite("--D", "2.7"), 2.7);
    EXPECT_DOUBLE_EQ(parse_finite("--theta", "-5.5"), -5.5);
    EXPECT_DOUBLE_EQ(parse_finite("--theta", "+60"), 60.0);
    EXPECT_DOUBLE_EQ(parse_finite("--D", "1e-1"), 0.1);
}

TEST(ParseFinite, RejectsNonFiniteAndGarbage) {
    for (const char* bad : {"nan", "NaN", "-nan", "inf", "-inf", "infinity", "1e999", "", "+",
                            "++1", "3cm", "abc", " 3", "0x1p3", "1,5"}) {
        const std::string msg = error_of([&] { parse_finite("--theta", bad); });
        EXPECT_NE(msg.find("--theta must be a finite number"), std::string::npos)
            << "'" << bad << "' gave '" << msg << "'";
    }
}

}  // namespace
}  // namespace hopper::cli
