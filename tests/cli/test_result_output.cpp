#include "cli/result_output.hpp"

#include <gtest/gtest.h>

#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace hopper::cli {
namespace {

using engine::Event;
using engine::RealizationResult;
using engine::Status;

RealizationResult fabricated() {
    RealizationResult r;
    r.status = Status::complete;
    r.message = "emptied \"ok\"";
    r.seed = 7;
    r.particles = 100;
    r.wall_particles = 40;
    r.survival_times = {0.5, 1.25};
    r.censored = {false, true};
    r.jam_onsets = {0.5};
    r.shakes_per_jam = {2};
    r.n_jams = 1;
    r.n_shakes = 2;
    r.n_jams_multi_shake = 1;
    r.empty_time = 1.75;
    r.discharge_rate = 57.0;
    r.discharge_rate_mass = 0.0068;
    r.discharged = 100;
    r.exit_times = {0.1, 0.2};
    r.curve_time = {0.0, 0.01};
    r.curve_count = {100, 99};
    r.events = {Event{Event::Kind::opened, 0.0, 0.3, 100}, Event{Event::Kind::jam, 0.5, 0.8, 60}};
    r.diagnostics.steps = 123456;
    r.diagnostics.wall_seconds = 1.5;
    r.diagnostics.ns_per_particle_step = 98.5;
    r.diagnostics.seconds_forces = 0.7;
    r.diagnostics.dt = 1.6e-5;
    return r;
}

const RunRequest request{"campaigns/tiny.toml", 3.0, 60.0, 7};

std::vector<std::string> lines_of(const std::string& s) {
    std::vector<std::string> v;
    std::istringstream is(s);
    for (std::string l; std::getline(is, l);)
        v.push_back(l);
    return v;
}

TEST(ResultJson, HasEveryRequiredKeyOnItsOwnLine) {
    const std::string json = result_json(request, fabricated());
    for (const char* key :
         {"status",         "message",         "D_cm",           "theta_deg",
          "seed",           "particles",       "n_jams",         "survival_times",
          "censored",       "jam_onsets",      "n_shakes",       "n_jams_multi_shake",
          "shakes_per_jam", "empty_time",      "discharge_rate", "discharge_rate_kg_s",
          "discharged",     "steps",           "wall_seconds",   "ns_per_particle_step",
          "diagnostics",    "discharge_curve", "events"}) {
        EXPECT_NE(json.find("\n  \"" + std::string(key) + "\": "), std::string::npos) << key;
    }
    EXPECT_NE(json.find(R"("status": "complete")"), std::string::npos);
    EXPECT_NE(json.find(R"("message": "emptied \"ok\"")"), std::string::npos);
    EXPECT_NE(json.find(R"("survival_times": [0.5, 1.25])"), std::string::npos);
    EXPECT_NE(json.find(R"("censored": [false, true])"), std::string::npos);
    EXPECT_NE(json.find(R"("in_hopper": [100, 99])"), std::string::npos);
    EXPECT_NE(json.find(R"({"kind": "jam", "time": 0.5, "sim_time": 0.8, "in_hopper": 60})"),
              std::string::npos);
    EXPECT_NE(json.find(R"("discharge_rate_kg_s": 0.0068)"), std::string::npos);
    EXPECT_EQ(json.front(), '{');
    EXPECT_EQ(json.back(), '}');
}

TEST(ResultJson, DiagnosticsHaveEveryField) {
    const std::string json = result_json(request, fabricated());
    for (const char* key :
         {"steps", "settle_steps", "neighbor_rebuilds", "settle_time", "shake_time", "wall_seconds",
          "ns_per_particle_step", "max_overlap_ratio", "settled_kinetic_energy",
          "potential_energy_released", "dt", "tau_c", "k_n", "seconds_forces",
          "seconds_integration", "seconds_neighbors", "seconds_observers"}) {
        EXPECT_NE(json.find("\n    \"" + std::string(key) + "\": "), std::string::npos) << key;
    }
}

TEST(ResultJson, MissingValuesAreNull) {
    RealizationResult r = fabricated();
    r.status = Status::arrested;
    r.empty_time.reset();
    r.discharge_rate.reset();
    r.discharge_rate_mass = 0.0;
    const std::string json = result_json(request, r);
    EXPECT_NE(json.find(R"("empty_time": null)"), std::string::npos);
    EXPECT_NE(json.find(R"("discharge_rate": null)"), std::string::npos);
    EXPECT_NE(json.find(R"("discharge_rate_kg_s": null)"), std::string::npos);
    EXPECT_NE(json.find(R"("status": "arrested")"), std::string::npos);
}

TEST(ResultJson, NeverPrintsNonFiniteNumbers) {
    RealizationResult r = fabricated();
    r.diagnostics.max_overlap_ratio = std::numeric_limits<double>::quiet_NaN();
    r.survival_times[0] = std::numeric_limits<double>::infinity();
    const std::string json = result_json(request, r);
    EXPECT_EQ(json.find("nan"), std::string::npos);
    EXPECT_EQ(json.find("inf"), std::string::npos);
    EXPECT_NE(json.find(R"("max_overlap_ratio": null)"), std::string::npos);
}

TEST(ResultJson, WallClockFieldsAreIsolatedAndTheRestIsReproducible) {
    RealizationResult a = fabricated(), b = fabricated();
    b.diagnostics.wall_seconds = 9.0;
    b.diagnostics.ns_per_particle_step = 1234.0;
    b.diagnostics.seconds_forces = 3.0;
    b.diagnostics.seconds_observers = 0.25;
    const auto la = lines_of(result_json(request, a)), lb = lines_of(result_json(request, b));
    ASSERT_EQ(la.size(), lb.size());
    int differing = 0;
    for (std::size_t i = 0; i < la.size(); ++i) {
        if (la[i] == lb[i]) continue;
        ++differing;
        // A differing line holds exactly one wall-clock key and its number.
        const auto q1 = la[i].find('"'), q2 = la[i].find('"', q1 + 1);
        ASSERT_NE(q2, std::string::npos) << la[i];
        EXPECT_TRUE(is_wall_clock_key(la[i].substr(q1 + 1, q2 - q1 - 1))) << la[i];
        EXPECT_EQ(la[i].find('"', q2 + 1), std::string::npos) << la[i];
    }
    EXPECT_EQ(differing, 6);  // wall_seconds, ns_per_particle_step twice; two seconds_*
    EXPECT_TRUE(is_wall_clock_key("seconds_neighbors"));
    EXPECT_FALSE(is_wall_clock_key("settle_time"));
}

TEST(ResultJson, NumbersFollowTheAnalysisRule) {
    const std::string json = result_json(request, fabricated());
    EXPECT_NE(json.find("\n  \"D_cm\": 3,\n"), std::string::npos) << json;  // not 3.0
    EXPECT_NE(json.find("\n  \"theta_deg\": 60,\n"), std::string::npos);
    EXPECT_NE(json.find("\n    \"dt\": 1.6e-05,\n"), std::string::npos);
    EXPECT_NE(json.find(R"("time": [0, 0.01])"), std::string::npos);
}

TEST(ResultJson, NonFiniteNumbersInArraysAreNull) {
    RealizationResult r = fabricated();
    r.survival_times = {std::numeric_limits<double>::quiet_NaN(), 1.5,
                        -std::numeric_limits<double>::infinity()};
    const std::string json = result_json(request, r);
    EXPECT_NE(json.find(R"("survival_times": [null, 1.5, null])"), std::string::npos) << json;
    EXPECT_EQ(json.find("nan"), std::string::npos);
    EXPECT_EQ(json.find("inf"), std::string::npos);
}

TEST(ResultJson, EventsOneObjectPerLineAndEmptyArraysInline) {
    RealizationResult r = fabricated();
    r.exit_times.clear();
    const std::string json = result_json(request, r);
    EXPECT_NE(json.find("\n  \"events\": [\n    {\"kind\": \"opened\", \"time\": 0, "
                        "\"sim_time\": 0.3, \"in_hopper\": 100},\n    {\"kind\": \"jam\", "
                        "\"time\": 0.5, \"sim_time\": 0.8, \"in_hopper\": 60}\n  ]"),
              std::string::npos)
        << json;
    EXPECT_NE(json.find("\n  \"exit_times\": [],\n"), std::string::npos);
    EXPECT_NE(json.find("\n  \"discharge_curve\": {\n    \"time\": [0, 0.01],\n    "
                        "\"in_hopper\": [100, 99]\n  },\n"),
              std::string::npos);
    EXPECT_EQ(json.find("\"fields\""), std::string::npos);  // no fields sampled: no key
}

TEST(ResultJson, ParsesBackToTheSameValues) {
    RealizationResult r = fabricated();
    const std::string text("tab\tnewline\nquote\" nul\0 end", 27);
    r.message = text + "\xff";  // \xff: not UTF-8
    r.survival_times = {0.1, 1.0 / 3.0, 6.02214076e23, 5e-324};
    const analysis::Json j = analysis::Json::parse(result_json(request, r));
    EXPECT_EQ(j["message"].get<std::string>(), text + "\xef\xbf\xbd");  // U+FFFD
    ASSERT_EQ(j["survival_times"].size(), r.survival_times.size());
    for (std::size_t i = 0; i < r.survival_times.size(); ++i)
        EXPECT_EQ(j["survival_times"][i].get<double>(), r.survival_times[i]);  // bit for bit
    EXPECT_EQ(j["censored"], analysis::Json::array({false, true}));
    EXPECT_EQ(j["seed"].get<std::uint64_t>(), 7u);
    EXPECT_EQ(j["diagnostics"]["steps"].get<std::int64_t>(), 123456);
    EXPECT_EQ(j.size(), result_object(request, r).size());
}

// The fields go in as the analysis layer's summary (analysis::add_fields_summary): nodes without
// windows do not count.
TEST(ResultJson, FieldsAsTheirSummary) {
    engine::FieldGrid g;
    g.x0 = -0.1;
    g.y0 = -0.0308;
    g.cell = 0.0154;
    g.nx = 3;
    g.ny = 2;
    engine::FieldMoments m = engine::FieldMoments::zero(g);
    m.windows = {0, 4, 1, 0, 2, 7};
    m.mean[static_cast<int>(engine::Field::speed)] = {9.0, 0.5, 0.25, 8.0, 0.75, 0.125};
    m.mean[static_cast<int>(engine::Field::pressure)] = {99.0, 3.0, 12.5, 0.0, 1.0, 2.0};
    m.samples = 120;
    m.total_windows = 12;
    m.t_first = 0.001;
    m.t_last = 0.12;
    RealizationResult r = fabricated();
    r.fields = m;
    const std::string json = result_json(request, r);
    EXPECT_NE(json.find("\n  \"fields\": {\"kernel\": \"cell\", \"cell_m\": 0.0154, \"x0_m\": "
                        "-0.1, \"y0_m\": -0.0308, \"nx\": 3, \"ny\": 2, \"samples\": 120, "
                        "\"total_windows\": 12, \"t_first\": 0.001, \"t_last\": 0.12, "
                        "\"cells_with_data\": 4, \"max_mean_speed\": 0.75, \"max_mean_pressure\": "
                        "12.5}\n}"),
              std::string::npos)
        << json;
    const analysis::Json f = analysis::Json::parse(json)["fields"];
    const analysis::Json expected = analysis::Json::parse(R"({"kernel": "cell", "cell_m": 0.0154,
        "x0_m": -0.1, "y0_m": -0.0308, "nx": 3, "ny": 2, "samples": 120, "total_windows": 12,
        "t_first": 0.001, "t_last": 0.12, "cells_with_data": 4, "max_mean_speed": 0.75,
        "max_mean_pressure": 12.5})");
    EXPECT_EQ(f, expected) << f.dump();
    const analysis::Json parsed = analysis::Json::parse(json);
    EXPECT_EQ(std::prev(parsed.end()).key(), "fields");  // the last member

    r.fields->grid.kernel = engine::FieldKernel::gaussian;
    r.fields->grid.kernel_width = 0.0077;
    r.fields->windows.assign(6, 0);
    const std::string gauss = result_json(request, r);
    EXPECT_NE(gauss.find("\"kernel\": \"gaussian\", \"kernel_width_m\": 0.0077,"),
              std::string::npos)
        << gauss;
    EXPECT_NE(gauss.find("\"cells_with_data\": 0, \"max_mean_speed\": 0, "
                         "\"max_mean_pressure\": 0}"),
              std::string::npos)
        << gauss;
}

TEST(Summary, NamesTheKeyQuantities) {
    std::ostringstream os;
    write_summary(os, request, fabricated());
    const std::string s = os.str();
    for (const char* text :
         {"status", "complete", "particles", "100", "jams", "shakes", "survival times",
          "0.5, 1.25 (censored)", "empty time", "1.75 s", "discharge rate", "57 particles/s",
          "steps", "123456", "wall time", "ns per particle-step", "98.5"}) {
        EXPECT_NE(s.find(text), std::string::npos) << text << "\n" << s;
    }
    EXPECT_GE(lines_of(s).size(), 10u);
}

}  // namespace
}  // namespace hopper::cli
