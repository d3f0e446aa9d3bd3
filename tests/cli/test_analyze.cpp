// `campaign analyze`'s pure part (cli/analyze.hpp) on fabricated realizations: what it takes
// from each result, the null-with-reason rule, grouping by wall angle, the Beverloo and jam-rate
// inputs, and the /analysis group it builds. The store and the executable are tested end to end
// by tests/campaign/analyze.sh.
#include <gtest/gtest.h>

#include <cmath>

#include "cli/analyze.hpp"

namespace hopper::cli {
namespace {

using engine::RealizationResult;
using engine::Status;

RealizationResult result(Status s, std::vector<double> t, bool last_censored = true) {
    RealizationResult r;
    r.status = s;
    r.survival_times = t;
    r.censored.assign(t.size(), false);
    if (last_censored && !t.empty()) r.censored.back() = true;
    double at = 0.0;
    for (std::size_t i = 0; i < t.size(); ++i) {
        at += t[i];
        if (!r.censored[i]) {
            r.jam_onsets.push_back(at);
            r.shakes_per_jam.push_back(1);
            ++r.n_jams;
            ++r.n_shakes;
        }
    }
    if (s == Status::complete) r.empty_time = at;
    return r;
}

std::map<std::string, std::string> scene() {
    return {{"particles.density_kg_m3", "1000"},
            {"particles.thickness_m", "0.0032"},
            {"particles.small_fraction", "0.5"},
            {"particles.d_small_m", "0.006"},
            {"particles.d_large_m", "0.008"}};
}

AnalysisPointInput point(double D, double theta, std::vector<RealizationResult> rs,
                         std::string extra = "") {
    AnalysisPointInput p;
    char buf[128];
    std::snprintf(buf, sizeof buf, "D_cm=%g theta_deg=%g", D, theta);
    p.label = buf + extra;
    p.scene = scene();
    p.D_cm = D;
    p.theta_deg = theta;
    p.planned = static_cast<int>(rs.size());
    p.results = std::move(rs);
    return p;
}

TEST(Analyze, TauIsTotalTimeOverJamsAndFailedRealizationsAreLeftOut) {
    auto failed = result(Status::failed, {5.0, 5.0});
    const Analysis a =
        analyze_points({point(2.0, 60,
                              {result(Status::complete, {1.0, 2.0}),
                               result(Status::arrested, {0.5, 1.5, 3.0}, false), failed})});
    ASSERT_EQ(a.points.size(), 1u);
    const PointAnalysis& p = a.points[0];
    EXPECT_EQ(p.stored, 3);
    EXPECT_EQ(p.n_complete, 1);
    EXPECT_EQ(p.n_arrested, 1);
    EXPECT_EQ(p.n_failed, 1);
    EXPECT_EQ(p.used, 2);
    EXPECT_EQ(p.n_jams, 4);  // 1 + 3 (the arrested one ends in a jam)
    ASSERT_TRUE(p.fit && p.fit->tau);
    EXPECT_DOUBLE_EQ(p.fit->total_observed_time, 8.0);
    EXPECT_DOUBLE_EQ(*p.fit->tau, 8.0 / 4.0);
    EXPECT_DOUBLE_EQ(*p.fit->mean_all, 8.0 / 5.0);
    EXPECT_EQ(p.empty_time.n, 1);
    EXPECT_DOUBLE_EQ(p.rho_b, 0.82 * 1000 * 0.0032);
    EXPECT_DOUBLE_EQ(p.d_mean, 0.007);
}

TEST(Analyze, NoJamsGivesNullWithReasonNeverANumber) {
    const Analysis a = analyze_points(
        {point(4.0, 60, {result(Status::complete, {1.0}), result(Status::complete, {1.2})})});
    const std::string j = analysis_json(a, "s.h5", "x");
    EXPECT_NE(j.find("\"tau_mle\": null"), std::string::npos) << j;
    EXPECT_NE(j.find("\"tau_mle_reason\": \"no jams\""), std::string::npos);
    EXPECT_NE(j.find("\"tau_ci95\": null"), std::string::npos);
    EXPECT_NE(j.find("\"gof_p\": null"), std::string::npos);
    EXPECT_NE(j.find("\"gof_p_reason\""), std::string::npos);
    EXPECT_NE(j.find("\"tau_lower_bound95\""), std::string::npos);
    EXPECT_EQ(j.find("nan"), std::string::npos);
    EXPECT_EQ(j.find("inf"), std::string::npos);
    // The jam-rate fit leaves the point out and says why.
    ASSERT_EQ(a.groups.size(), 1u);
    ASSERT_EQ(a.groups[0].jam_rate_left_out.size(), 1u);
    EXPECT_EQ(a.groups[0].jam_rate_left_out[0].second, "no jams");
}

TEST(Analyze, GroupsByWallAngleAndOtherVariedSettingsFromTheLabel) {
    const Analysis a = analyze_points(
        {point(2.0, 44.99999999999999, {result(Status::complete, {1.0})}, " material.mu=0.5"),
         point(3.0, 45, {result(Status::complete, {1.0})}, " material.mu=0.5"),
         point(2.0, 45, {result(Status::complete, {1.0})}, " material.mu=0.3")});
    ASSERT_EQ(a.groups.size(), 2u);
    EXPECT_EQ(a.groups[0].group, "theta_deg=45 material.mu=0.5");
    EXPECT_EQ(a.groups[0].points.size(), 2u);
    EXPECT_EQ(a.points[0].theta_deg, 45.0);  // from the label, not the SI round trip
    const std::string j = analysis_json(a, "s.h5", "x");
    EXPECT_NE(j.find("\"material.mu\": 0.5"), std::string::npos) << j;
}

TEST(Analyze, BeverlooFitRecoversAnExactLaw) {
    const double C = 0.7, k = 1.5, rho_b = 0.82 * 1000 * 0.0032, d = 0.007;
    std::vector<AnalysisPointInput> pts;
    for (double D : {2.0, 3.0, 4.0, 5.0}) {
        auto r = result(Status::complete, {1.0});
        const double W = C * rho_b * std::sqrt(9.80665) * std::pow(D * 0.01 - k * d, 1.5);
        r.discharge_rate = W / 1e-3;
        r.discharge_rate_mass = W;
        pts.push_back(point(D, 60, {r, r}));
    }
    const Analysis a = analyze_points(pts);
    ASSERT_EQ(a.groups.size(), 1u);
    const auto& b = a.groups[0].beverloo;
    ASSERT_TRUE(b.valid) << b.reason;
    EXPECT_EQ(b.n_points, 4);
    // The fit's own convergence tolerance (stats tests) bounds the agreement, not the inputs.
    EXPECT_NEAR(b.C, C, 1e-3 * C);
    EXPECT_NEAR(b.k, k, 1e-3 * k);
    EXPECT_DOUBLE_EQ(b.rho_b, rho_b);
    EXPECT_DOUBLE_EQ(b.d, d);
}

TEST(Analyze, GroupHasOneRowPerPointAndFlagsForMissingValues) {
    const Analysis a = analyze_points(
        {point(2.0, 60, {result(Status::complete, {0.2, 0.3, 0.1, 0.4, 0.2, 0.5, 1.0})}),
         point(4.0, 60, {result(Status::complete, {1.0})})});
    const store::DerivedGroup g = analysis_group(a, "{}");
    EXPECT_EQ(g.name, "analysis");
    ASSERT_EQ(g.groups.size(), 4u);
    const auto& points = g.groups[0];
    EXPECT_EQ(points.name, "points");
    bool saw_has_tau = false;
    for (const auto& d : points.datasets) {
        std::size_t n = 0;
        std::visit([&](const auto& v) { n = v.size(); }, d.values);
        EXPECT_EQ(n, 2u) << d.name;
        EXPECT_FALSE(d.description.empty()) << d.name;
        if (d.name == "has_tau_mle") {
            saw_has_tau = true;
            const auto& v = std::get<std::vector<bool>>(d.values);
            EXPECT_TRUE(v[0]);
            EXPECT_FALSE(v[1]);
        }
        if (const auto* v = std::get_if<std::vector<double>>(&d.values)) {
            for (double x : *v)
                EXPECT_TRUE(std::isfinite(x)) << d.name;
        }
    }
    EXPECT_TRUE(saw_has_tau);
    // The Kaplan–Meier steps of point 0 (5 distinct jam times) and none for point 1.
    EXPECT_EQ(std::get<std::vector<double>>(g.groups[1].datasets[0].values).size(), 5u);
}

}  // namespace
}  // namespace hopper::cli
