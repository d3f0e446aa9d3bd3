#include "cli/deadline.hpp"

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
    "@SECONDS_SINCE_1970, an ISO 8601 UTC time such as "
    "2026-11-24T15:00:00Z, or a time from now such as +3600, +90m, +2h, +1:30:00";

[[noreturn]] void bad(const std::string& text, const std::string& why) {
    throw core::ConfigError("--deadline '" + text + "': " + why + " (" + forms + ")");
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
            before = std::stod(m[1].str()) * (unit == "m" ? 60.0 : unit == "h" ? 3600.0 : 1.0);
        }
        std::string why;
        if (auto t = slurm_job_end(&why)) return *t - before;
        bad(text, "the Slurm job's end time is unknown: " + why);
    }
    if (std::regex_match(text, m, std::regex(R"(@([0-9]+(\.[0-9]+)?))")))
        return std::stod(m[1].str());
    if (std::regex_match(text,
                         std::regex(R"([0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}Z)"))) {
        std::tm tm{};
        if (!strptime(text.c_str(), "%Y-%m-%dT%H:%M:%SZ", &tm)) bad(text, "not a valid time");
        return static_cast<double>(timegm(&tm));
    }
    if (std::regex_match(text, m, std::regex(R"(\+([0-9]+(\.[0-9]+)?)([smh]?))"))) {
        const double v = std::stod(m[1].str());
        const std::string unit = m[3].str();
        const double f = unit == "m" ? 60.0 : unit == "h" ? 3600.0 : 1.0;
        return now + v * f;
    }
    if (std::regex_match(text, m, std::regex(R"(\+([0-9]+):([0-5][0-9]):([0-5][0-9]))")))
        return now + 3600.0 * std::stod(m[1].str()) + 60.0 * std::stod(m[2].str()) +
               std::stod(m[3].str());
    bad(text, "not a deadline");
}

}  // namespace hopper::cli
