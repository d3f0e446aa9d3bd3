// --deadline's forms (issue 15; issue 29, items 3 and 4; issue 27, item 5): ISO 8601 with Z or a
// UTC offset, dates that do not exist refused, numbers too large for a deadline refused with the
// deadline's message (never an uncaught std::out_of_range), nothing after 9999-12-31.
#include "cli/deadline.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "hopper/core/error.hpp"

namespace hopper::cli {
namespace {

std::string error_of(const std::string& text) {
    try {
        parse_deadline(text, 1.0e9);
    } catch (const core::ConfigError& e) {
        return e.what();
    }
    return "";
}

TEST(ParseDeadline, IsoTimesWithZOrAUtcOffset) {
    const double t = 1795655996.0;  // 2026-11-26T01:19:56Z
    EXPECT_EQ(parse_deadline("2026-11-26T01:19:56Z", 0), t);
    EXPECT_EQ(parse_deadline("2026-11-26T01:19:56+00:00", 0), t);
    EXPECT_EQ(parse_deadline("2026-11-26T06:49:56+05:30", 0), t);
    EXPECT_EQ(parse_deadline("2026-11-25T20:19:56-05:00", 0), t);
    EXPECT_EQ(parse_deadline("2028-02-29T00:00:00Z", 0), 1835395200.0);  // a leap day
    EXPECT_EQ(parse_deadline("9999-12-31T23:59:59Z", 0), 253402300799.0);
}

TEST(ParseDeadline, DatesThatDoNotExistAreRefused) {
    for (const char* bad :
         {"2026-02-31T00:00:00Z", "2026-02-29T00:00:00Z", "2026-04-31T12:00:00Z",
          "2026-13-01T00:00:00Z", "2026-00-10T00:00:00Z", "2026-11-26T24:00:00Z",
          "2026-11-26T10:60:00Z", "2026-11-26T10:00:60Z", "2026-11-26T10:00:00+24:00",
          "2026-11-26T10:00:00+05:60", "2026-11-26T10:00:00+2400", "2026-11-26T10:00:00+053",
          "2026-11-26T10:00:00.Z", "2026-11-26 10:00:00Z", "+1w", "+1dd"}) {
        const std::string m = error_of(bad);
        EXPECT_NE(m.find("--deadline '" + std::string(bad) + "'"), std::string::npos)
            << bad << ": " << m;
        EXPECT_NE(m.find("allowed:"), std::string::npos) << m;
    }
}

TEST(ParseDeadline, AbsurdNumbersGiveTheDeadlineError) {
    const std::string digits(400, '9');
    for (const std::string& bad : std::vector<std::string>{
             "@" + digits, "+" + digits, "+" + digits + "h", "+99999999999999999999h",
             "@99999999999999999999", "+" + digits + ":00:00", "@253402300800",
             "10000-01-01T00:00:00Z"}) {
        const std::string m = error_of(bad);
        EXPECT_NE(m.find("--deadline '" + bad + "'"), std::string::npos) << bad << ": " << m;
    }
    EXPECT_NE(error_of("+99999999999999999999h").find("later than the year 9999"),
              std::string::npos);
    EXPECT_EQ(parse_deadline("@99999999999", 0), 99999999999.0);  // year 5138: taken
}

// Issue 43, item 8: what `date +%FT%T%z` prints (+0100, no colon), fractional seconds, local
// times without a zone (the TZ of the machine; a POSIX rule here, so no zone files are needed),
// days and fractions of them from now.
TEST(ParseDeadline, DateCommandOffsetsFractionsLocalTimesAndDays) {
    const double t = 1795655996.0;  // 2026-11-26T01:19:56Z
    EXPECT_EQ(parse_deadline("2026-11-26T02:19:56+0100", 0), t);
    EXPECT_EQ(parse_deadline("2026-11-25T20:19:56-0500", 0), t);
    EXPECT_EQ(parse_deadline("2026-11-26T01:19:56.25Z", 0), t + 0.25);
    EXPECT_EQ(parse_deadline("2026-11-26T02:19:56.5+01:00", 0), t + 0.5);
    EXPECT_EQ(parse_deadline("+1d", 1.0e9), 1.0e9 + 86400.0);
    EXPECT_EQ(parse_deadline("+1.5d", 1.0e9), 1.0e9 + 1.5 * 86400.0);
    EXPECT_EQ(parse_deadline("+36h", 1.0e9), 1.0e9 + 36 * 3600.0);

    const char* old_tz = std::getenv("TZ");
    const std::string saved = old_tz ? old_tz : "";
    setenv("TZ", "CET-1CEST,M3.5.0,M10.5.0/3", 1);  // Central Europe: UTC+1, summer UTC+2
    tzset();
    const double winter = parse_deadline("2026-11-26T02:19:56", 0).value();
    const double summer = parse_deadline("2026-07-01T14:00:00", 0).value();  // 12:00Z
    const std::string gap = error_of("2026-03-29T02:30:00");  // skipped: 02:00 -> 03:00
    if (old_tz)
        setenv("TZ", saved.c_str(), 1);
    else
        unsetenv("TZ");
    tzset();
    EXPECT_EQ(winter, t);
    EXPECT_EQ(summer, 1782907200.0);
    EXPECT_NE(gap.find("not a valid local date and time"), std::string::npos) << gap;
}

}  // namespace
}  // namespace hopper::cli
