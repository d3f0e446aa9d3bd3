#include "cli/deadline.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <regex>

#include "hopper/core/error.hpp"

namespace hopper::cli {

namespace {

const char* forms =
    "allowed: none, slurm, slurm-SECONDS (the job's end time minus SECONDS), "
    "@SECONDS_SINCE_1970, an ISO 8601 time such as 2026-11-24T15:00:00Z, "
    "2026-11-24T16:00:00+01:00 or +0100 (what date +%FT%T%z prints), 2026-11-24T16:00:00.5Z, "
    "or without a zone 2026-11-24T16:00:00 (this machine's local time), "
    "or a time from now such as +3600, +90m, +2h, +36h, +1d, +1.5d, +1:30:00; "
    "no later than 9999-12-31T23:59:59Z";

// 9999-12-31T23:59:59Z: the latest deadline taken (an ISO 8601 year has four digits); later
// ones are typing errors, and beyond about 2^63 ns every clock of the master would overflow.
constexpr double latest = 253402300799.0;

[[noreturn]] void bad(const std::string& text, const std::string& why) {
    throw core::ConfigError("--deadline '" + text + "': " + why + " (" + forms + ")");
}

// A number the regular expressions matched (digits, maybe a fraction): one too large for a
// double, or for a deadline, is refused like any other bad value.
double number(const std::string& text, const std::string& digits) {
    if (digits.size() > 30) bad(text, "the number is too large");
    return std::strtod(digits.c_str(), nullptr);
}

// A deadline in range: finite, not after `latest`.
double checked(const std::string& text, double t) {
    if (!std::isfinite(t) || t > latest) bad(text, "later than the year 9999");
    return t;
}

// Seconds since 1970 of a calendar date and time in UTC, or nullopt when the date does not exist
// (2026-02-31, 2026-13-01, 24:00:00): timegm normalizes those, so the fields must come back.
std::optional<double> utc_seconds(int y, int mo, int d, int h, int mi, int s) {
    std::tm tm{};
    tm.tm_year = y - 1900;
    tm.tm_mon = mo - 1;
    tm.tm_mday = d;
    tm.tm_hour = h;
    tm.tm_min = mi;
    tm.tm_sec = s;
    const std::time_t t = timegm(&tm);
    std::tm back{};
    if (!gmtime_r(&t, &back) || back.tm_year != y - 1900 || back.tm_mon != mo - 1 ||
        back.tm_mday != d || back.tm_hour != h || back.tm_min != mi || back.tm_sec != s)
        return std::nullopt;
    return static_cast<double>(t);
}

// The same for a calendar date and time in this machine's local time zone (TZ), or nullopt when
// it does not exist there (also an hour skipped by a change to daylight-saving time).
std::optional<double> local_seconds(int y, int mo, int d, int h, int mi, int s) {
    std::tm tm{};
    tm.tm_year = y - 1900;
    tm.tm_mon = mo - 1;
    tm.tm_mday = d;
    tm.tm_hour = h;
    tm.tm_min = mi;
    tm.tm_sec = s;
    tm.tm_isdst = -1;  // let the zone's rules say whether daylight-saving time applies
    const std::time_t t = std::mktime(&tm);
    std::tm back{};
    if (t == static_cast<std::time_t>(-1) || !localtime_r(&t, &back) || back.tm_year != y - 1900 ||
        back.tm_mon != mo - 1 || back.tm_mday != d || back.tm_hour != h || back.tm_min != mi ||
        back.tm_sec != s)
        return std::nullopt;
    return static_cast<double>(t);
}

double unit_seconds(const std::string& unit) {
    return unit == "m" ? 60.0 : unit == "h" ? 3600.0 : unit == "d" ? 86400.0 : 1.0;
}

}  // namespace

std::optional<double> slurm_job_end(std::string* why) {
    auto say = [&](const std::string& w) {
        if (why) *why = w;
        return std::nullopt;
    };
    const char* job = std::getenv("SLURM_JOB_ID");
    if (!job || !*job) return say("not inside a Slurm job (SLURM_JOB_ID is not set)");
    if (const char* end = std::getenv("SLURM_JOB_END_TIME"); end && *end) {
        char* stop = nullptr;
        const double v = std::strtod(end, &stop);
        if (stop && *stop == '\0' && v > 0) return v;
    }
    const std::string id = job;
    for (char c : id)
        if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '_'))
            return say("SLURM_JOB_ID '" + id + "' is not a job id");
    const std::string cmd = "squeue -h -j " + id + " -o %e 2>/dev/null";
    std::unique_ptr<FILE, int (*)(FILE*)> p(::popen(cmd.c_str(), "r"), ::pclose);
    if (!p) return say("cannot run squeue");
    char buf[128] = {};
    if (!std::fgets(buf, sizeof buf, p.get())) return say("squeue gave no end time for job " + id);
    std::tm tm{};
    if (!strptime(buf, "%Y-%m-%dT%H:%M:%S", &tm))
        return say("squeue's end time '" + std::string(buf) + "' is not a time (no limit?)");
    tm.tm_isdst = -1;
    const std::time_t t = std::mktime(&tm);  // squeue prints local time
    if (t <= 0) return say("squeue's end time cannot be converted");
    return static_cast<double>(t);
}

std::optional<double> parse_deadline(const std::string& text, double now) {
    if (text == "none") return std::nullopt;
    std::smatch m;
    if (text == "slurm" ||
        std::regex_match(text, m, std::regex(R"(slurm-([0-9]+(\.[0-9]+)?)([smh]?))"))) {
        double before = 0.0;
        if (text != "slurm") {
            const std::string unit = m[3].str();
            before = number(text, m[1].str()) * unit_seconds(unit);
        }
        std::string why;
        if (auto t = slurm_job_end(&why)) return *t - before;
        bad(text, "the Slurm job's end time is unknown: " + why);
    }
    if (std::regex_match(text, m, std::regex(R"(@([0-9]+(\.[0-9]+)?))")))
        return checked(text, number(text, m[1].str()));
    // ISO 8601: date, T, time with optional fractional seconds, then Z, an offset +hh:mm or
    // +hhmm, or nothing (local time).
    if (std::regex_match(
            text, m,
            std::regex(R"(([0-9]{4})-([0-9]{2})-([0-9]{2})T([0-9]{2}):([0-9]{2}):)"
                       R"(([0-9]{2})(\.[0-9]{1,9})?(Z|([+-])([0-9]{2}):?([0-9]{2}))?)"))) {
        auto field = [&](int k) { return std::stoi(m[k].str()); };
        const bool local = !m[8].matched;
        const auto t =
            local ? local_seconds(field(1), field(2), field(3), field(4), field(5), field(6))
                  : utc_seconds(field(1), field(2), field(3), field(4), field(5), field(6));
        if (!t)
            bad(text, local ? "not a valid local date and time (no such day, hour, minute or "
                              "second here, or an hour skipped by daylight-saving time)"
                            : "not a valid date and time (no such day, hour, minute or second)");
        const double fraction = m[7].matched ? std::strtod(m[7].str().c_str(), nullptr) : 0.0;
        double offset = 0.0;  // local time = UTC + offset
        if (!local && m[8].str() != "Z") {
            if (field(10) > 23 || field(11) > 59) bad(text, "not a valid UTC offset");
            offset = (m[9].str() == "-" ? -1.0 : 1.0) * (3600.0 * field(10) + 60.0 * field(11));
        }
        return checked(text, *t + fraction - offset);
    }
    if (std::regex_match(text, m, std::regex(R"(\+([0-9]+(\.[0-9]+)?)([smhd]?))"))) {
        const double v = number(text, m[1].str());
        return checked(text, now + v * unit_seconds(m[3].str()));
    }
    if (std::regex_match(text, m, std::regex(R"(\+([0-9]+):([0-5][0-9]):([0-5][0-9]))")))
        return checked(text, now + 3600.0 * number(text, m[1].str()) +
                                 60.0 * number(text, m[2].str()) + number(text, m[3].str()));
    bad(text, "not a deadline");
}

}  // namespace hopper::cli
