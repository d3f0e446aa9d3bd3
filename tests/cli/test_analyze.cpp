// `campaign analyze`'s pure part (the analysis layer, hopper/analysis) on fabricated realizations:
// what it takes from each result, the null-with-reason rule, grouping by wall angle, the Beverloo
// and jam-rate inputs, and the /analysis group it builds. The store and the executable are tested
// end to end by tests/campaign/analyze.sh.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <sstream>
#include <utility>

#include <nlohmann/json.hpp>

#include "../store/fixtures.hpp"
#include "cli/analyze.hpp"
#include "hopper/analysis/analyze.hpp"
#include "hopper/analysis/derived.hpp"
#include "hopper/analysis/json.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"
#include "hopper/engine/fields.hpp"
#include "hopper/store/analysis.hpp"
#include "hopper/store/store.hpp"

namespace hopper::analysis {
namespace {

using cli::analyze_store;
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

// The scene parameters the Beverloo inputs come from (sweep-file names and units).
std::vector<core::Setting> parameters() {
    return {{"hopper.density_kg_m3", 1000.0},
            {"hopper.thickness_cm", 0.32},
            {"hopper.small_fraction", 0.5},
            {"hopper.d_small_cm", 0.6},
            {"hopper.d_large_cm", 0.8}};
}

// A point whose settings are D and theta as a user writes them ("%g"), plus `extra`; the plan's
// SI round trip (D_cm, theta_deg of the input) keeps the values given.
AnalysisPointInput point(double D, double theta, std::vector<RealizationResult> rs,
                         std::vector<core::Setting> extra = {}) {
    AnalysisPointInput p;
    const auto written = [](double v) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%g", v);
        return std::stod(buf);
    };
    p.settings = {{"D_cm", written(D)}, {"theta_deg", written(theta)}};
    p.settings.insert(p.settings.end(), extra.begin(), extra.end());
    for (const auto& s : p.settings) {
        if (!p.label.empty()) p.label += ' ';
        p.label += config::to_string(s);
    }
    p.parameters = parameters();
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
        {point(2.0, 44.99999999999999, {result(Status::complete, {1.0})}, {{"material.mu", 0.5}}),
         point(3.0, 45, {result(Status::complete, {1.0})}, {{"material.mu", 0.5}}),
         point(2.0, 45, {result(Status::complete, {1.0})}, {{"material.mu", 0.3}})});
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
    ASSERT_EQ(g.groups.size(), 5u);
    EXPECT_EQ(g.groups[4].name, "avalanche");
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

// ----- avalanches and arches (issue 13) ---------------------------------------------------------

// A result whose intervals have the given avalanche sizes (the last censored) and one arch of
// `disks` disks per jam.
RealizationResult with_sizes(std::vector<int> sizes, int disks = 3) {
    std::vector<double> t(sizes.size(), 0.5);
    RealizationResult r = result(Status::complete, t);
    r.avalanche_sizes = sizes;
    for (int k = 0; k < r.n_jams; ++k) {
        engine::Arch a;
        for (int i = 0; i < disks; ++i) {
            a.ids.push_back(i);
            a.x.push_back(0.0);
            a.y.push_back(0.0);
        }
        a.span = 0.02;
        a.max_angle = 3.0 * core::deg * 50;  // 150 deg
        r.arches.push_back(a);
    }
    return r;
}

TEST(AnalyzeAvalanches, MeanSizeIsGrainsPerJamWithTheChiSquareInterval) {
    // Two realizations: sizes {10, 30, 5 censored} and {20, 35 censored}: S = 100 grains,
    // r = 3 jams: <s> = 33.33, s.e. <s>/sqrt(3) = 19.25, p = 0.03; the interval
    // [2S/chi2_0.975(6), 2S/chi2_0.025(6)] = [200/14.449, 200/1.2373] = [13.84, 161.6].
    const Analysis a =
        analyze_points({point(2.0, 60, {with_sizes({10, 30, 5}), with_sizes({20, 35}, 4)})});
    const auto& av = a.points[0].avalanche;
    ASSERT_TRUE(av.fit && av.fit->tau) << av.reason;
    EXPECT_EQ(av.realizations, 2);
    EXPECT_DOUBLE_EQ(av.fit->total_observed_time, 100.0);
    EXPECT_EQ(av.fit->n_uncensored, 3);
    EXPECT_NEAR(*av.fit->tau, 100.0 / 3.0, 1e-12);
    EXPECT_NEAR(*av.fit->tau * *av.fit->sigma_log_tau, 100.0 / 3.0 / std::sqrt(3.0), 1e-9);
    EXPECT_NEAR(*av.fit->tau_lo, 200.0 / 14.4494, 0.01);
    EXPECT_NEAR(*av.fit->tau_hi, 200.0 / 1.23734, 0.1);
    // Arches: 2 jams with 3 disks, 1 with 4.
    EXPECT_EQ(av.arch_jams, 3);
    EXPECT_EQ(av.arches_found, 3);
    ASSERT_EQ(av.arch_size_counts.size(), 5u);
    EXPECT_EQ(av.arch_size_counts[3], 2);
    EXPECT_EQ(av.arch_size_counts[4], 1);
    EXPECT_NEAR(*av.arch_mean_size, 10.0 / 3.0, 1e-12);
    EXPECT_NEAR(*av.arch_mean_max_angle_deg, 150.0, 1e-9);
    const std::string json = analysis_json(a, "s.h5", "c");
    EXPECT_NE(json.find("\"p_clog_per_grain\": 0.03"), std::string::npos) << json;
    EXPECT_EQ(nlohmann::json::parse(json)["points"][0]["avalanche"]["arches"]["size_counts"],
              (nlohmann::json{{"3", 2}, {"4", 1}}))
        << json;
}

TEST(AnalyzeAvalanches, ResultsWithoutSizesAreCountedAndLeftOut) {
    // Stored before issue 13: no avalanche sizes, no arches.
    const Analysis a = analyze_points({point(2.0, 60, {result(Status::complete, {0.2, 0.3})})});
    const auto& av = a.points[0].avalanche;
    EXPECT_FALSE(av.fit);
    EXPECT_EQ(av.realizations_without, 1);
    EXPECT_NE(av.reason.find("stored before avalanche sizes"), std::string::npos);
    const std::string json = analysis_json(a, "s.h5", "c");
    EXPECT_NE(json.find("\"mean_s\": null"), std::string::npos);
}

TEST(AnalyzeAvalanches, MeanSizeVersusDFitsTheExponentialExactly) {
    // <s> = 10 e^(B D) with B = 100 /m: ln p = -ln 10 - B D exactly. Every point has r = 4 jams
    // (sizes s each, censored 0) at five outlets: both laws fitted, a decision made.
    std::vector<AnalysisPointInput> pts;
    for (double D : {2.0, 2.2, 2.4, 2.6, 2.8}) {
        const int s = int(std::lround(10.0 * std::exp(100.0 * D / 100.0)));
        pts.push_back(point(D, 60, {with_sizes({s, s, s, s, 0})}));
    }
    const Analysis a = analyze_points(pts);
    ASSERT_EQ(a.groups.size(), 1u);
    const auto& f = a.groups[0].avalanche;
    EXPECT_EQ(f.n_points, 5);
    ASSERT_TRUE(f.exponential.valid) << f.exponential.reason;
    EXPECT_NEAR(f.exponential.B, 100.0, 0.5);  // sizes rounded to whole grains
    EXPECT_NEAR(-f.exponential.ln_A, std::log(10.0), 0.02);
    EXPECT_NE(f.preferred, "");
    const std::string json = analysis_json(a, "s.h5", "c");
    EXPECT_NE(json.find("\"avalanche_fits\""), std::string::npos);
    EXPECT_NE(json.find("\"ln_s0\""), std::string::npos);
    // Four points: too few to decide, said so.
    pts.pop_back();
    const Analysis b = analyze_points(pts);
    EXPECT_EQ(b.groups[0].avalanche.preferred, "undecided");
    EXPECT_NE(b.groups[0].avalanche.decision.find("too few points"), std::string::npos);
}

// Issue 16 leftover: points pooled with --allow-mixed whose labels do not show a difference.
TEST(AnalyzeGroups, SettingsTheLabelsHideSplitTheGroups) {
    auto with_mu = [](double D, double mu) {
        AnalysisPointInput p = point(D, 60, {result(Status::complete, {0.2, 0.3})});
        p.parameters.push_back({"material.mu", mu});
        return p;
    };
    const Analysis a = analyze_points({with_mu(2.0, 0.8), with_mu(2.5, 0.8), with_mu(3.0, 0.5)});
    ASSERT_EQ(a.groups.size(), 2u);
    EXPECT_EQ(a.groups[0].group, "theta_deg=60 material.mu=0.8");
    EXPECT_EQ(a.groups[0].points.size(), 2u);
    EXPECT_EQ(a.groups[1].group, "theta_deg=60 material.mu=0.5");
    // Labels that show every difference: nothing added (groups as before).
    const Analysis b = analyze_points({with_mu(2.0, 0.8), with_mu(2.5, 0.8), [&] {
                                           AnalysisPointInput p =
                                               point(3.0, 30, {result(Status::complete, {0.2})});
                                           p.parameters.push_back({"material.mu", 0.5});
                                           return p;
                                       }()});
    ASSERT_EQ(b.groups.size(), 2u);
    EXPECT_EQ(b.groups[0].group, "theta_deg=60");
    EXPECT_EQ(b.groups[1].group, "theta_deg=30");
}

// ----- fields (issue 7) -------------------------------------------------------------------------

engine::FieldGrid field_grid(engine::FieldKernel kernel) {
    engine::FieldGrid g;
    g.x0 = -0.04;
    g.y0 = -0.02;
    g.cell = 0.01;
    g.nx = 8;
    g.ny = 6;
    g.kernel = kernel;
    g.kernel_width = kernel == engine::FieldKernel::gaussian ? 0.008 : 0.0;
    return g;
}

// Times and windows are binary fractions (samples every 1/1024 s, windows of 1/128 s: 8 samples),
// so a realization fed at a later time t0 falls into windows exactly as it does alone.
constexpr double sample_dt = 1.0 / 1024, window = 1.0 / 128;

// Feeds `count` samples of a made-up discharge (30 particles, some outside the grid) at times
// t0, t0 + sample_dt, ... into `acc`.
void feed(engine::FieldAccumulator& acc, std::uint64_t seed, double t0, int count) {
    std::mt19937_64 gen(seed);
    auto u = [&](double lo, double hi) {
        return lo + (hi - lo) * static_cast<double>(gen() >> 11) * 0x1.0p-53;
    };
    constexpr int n = 30;
    std::vector<double> x(n), y(n), vx(n), vy(n), p(n);
    for (int i = 0; i < count; ++i) {
        for (int k = 0; k < n; ++k) {
            x[k] = u(-0.05, 0.05);
            y[k] = u(-0.03, 0.05);
            vx[k] = u(-0.2, 0.2);
            vy[k] = u(-0.8, 0.1);
            p[k] = u(0.0, 6.0);
        }
        acc.sample(t0 + sample_dt * i, x, y, vx, vy, p);
    }
}

// One realization's fields: its own accumulator, closed at the end (as the engine does).
engine::FieldMoments piece(engine::FieldKernel kernel, std::uint64_t seed, int count) {
    engine::FieldAccumulator acc(field_grid(kernel), window, 0.0);
    feed(acc, seed, 0.0, count);
    acc.close_window();
    engine::FieldMoments m = acc.moments();
    m.outline_x = {0.01, 0.04};
    m.outline_y = {0.0, 0.05};
    m.wall_diameter = 0.0077;
    return m;
}

// Both realizations' windows fed to one accumulator (the second shifted by whole windows).
engine::FieldMoments one_accumulator(engine::FieldKernel kernel, int count_a, int count_b) {
    engine::FieldAccumulator acc(field_grid(kernel), window, 0.0);
    feed(acc, 11, 0.0, count_a);
    feed(acc, 22, 16.0, count_b);
    acc.close_window();
    return acc.moments();
}

void expect_near(double a, double b, const std::string& what) {
    EXPECT_NEAR(a, b, 1e-12 * std::max(1.0, std::abs(b))) << what;
}

// Per-node windows, weight, mean and fluctuation agree to 1e-12 (relative).
void expect_same_moments(const engine::FieldMoments& a, const engine::FieldMoments& b) {
    ASSERT_EQ(a.grid, b.grid);
    EXPECT_EQ(a.windows, b.windows);
    EXPECT_EQ(a.total_windows, b.total_windows);
    EXPECT_EQ(a.samples, b.samples);
    for (int c = 0; c < a.grid.size(); ++c) {
        expect_near(a.weight[c], b.weight[c], "weight " + std::to_string(c));
        for (int f = 0; f < engine::field_count; ++f) {
            const auto field = static_cast<engine::Field>(f);
            expect_near(a.mean[f][c], b.mean[f][c], "mean " + std::to_string(c));
            expect_near(a.fluctuation(field, c), b.fluctuation(field, c),
                        "fluctuation " + std::to_string(c));
        }
    }
}

TEST(AnalyzeFields, MergingTwoRealizationsEqualsOneAccumulatorOverBoth) {
    for (auto kernel : {engine::FieldKernel::cell, engine::FieldKernel::gaussian}) {
        const auto a = piece(kernel, 11, 95), b = piece(kernel, 22, 57);
        AnalysisPointInput in =
            point(4.5, 60,
                  {result(Status::complete, {1.0}), result(Status::time_limit, {1.0}),
                   result(Status::failed, {1.0})});
        in.results[0].fields = a;
        in.results[1].fields = b;
        in.results[2].fields = piece(kernel, 33, 40);  // failed: left out
        const PointFields pf = merge_point_fields(in);
        ASSERT_TRUE(pf.merged.has_value());
        EXPECT_EQ(pf.realizations, 2);
        engine::FieldMoments direct = a;
        direct.merge(b);
        expect_same_moments(*pf.merged, direct);
        expect_same_moments(*pf.merged, one_accumulator(kernel, 95, 57));
        EXPECT_GT(pf.cells_with_data, 0);
        EXPECT_LT(pf.cells_with_data, pf.merged->grid.size() + 1);
    }
}

TEST(AnalyzeFields, GridsThatDifferInsideAPointAreAnErrorNamingThePointAndTheRows) {
    AnalysisPointInput in =
        point(4.5, 60, {result(Status::complete, {1.0}), result(Status::complete, {1.0})});
    in.results[0].fields = piece(engine::FieldKernel::cell, 1, 20);
    in.results[1].fields = piece(engine::FieldKernel::gaussian, 2, 20);
    in.rows = {4, 9};
    try {
        merge_point_fields(in);
        FAIL() << "merged different grids";
    } catch (const core::StoreError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("point 'D_cm=4.5 theta_deg=60'"), std::string::npos) << m;
        EXPECT_NE(m.find("rows 4 and 9"), std::string::npos) << m;
    }
    const Analysis a = analyze_points({in});
    EXPECT_TRUE(a.points[0].fields.error);
    EXPECT_FALSE(a.points[0].fields.merged.has_value());
    const std::string j = analysis_json(a, "s.h5", "x");
    EXPECT_NE(j.find("\"fields\": null"), std::string::npos) << j;
    EXPECT_NE(j.find("rows 4 and 9"), std::string::npos);
}

// A store written through the store's API: point F samples fields (two realizations with
// fields and a failed one), point N does not.
// Their typed settings and parameters as the plan records them.
store::PointPlan typed(store::PointPlan p, double D, bool fields) {
    p.settings = {{"D_cm", D}, {"theta_deg", 60.0}};
    p.parameters = {{"D_cm", D},
                    {"theta_deg", 60.0},
                    {"hopper.d_large_cm", 0.77},
                    {"fields.enabled", std::string(fields ? "true" : "false")}};
    return p;
}
const store::PointPlan F = typed(
    store::testing::point("D_cm=4.5 theta_deg=60", 3,
                          "particles.d_large_m=0.0077\nfields.window_s=0.01\nfields.cell_dlarge=2\n"
                          "fields.sample_interval_s=0.001\nfields.start_s=0\nfields.end_s="
                          "unset\nfields.kernel=cell\n"),
    4.5, true);
const store::PointPlan N = typed(store::testing::point("D_cm=3 theta_deg=60", 1), 3.0, false);

std::filesystem::path fields_store(bool with_fields) {
    using store::testing::fabricated;
    using store::testing::result_record;
    const auto path = store::testing::scratch() / "s.h5";
    store::Store s(path);
    s.begin_run(store::testing::run_record({N, F}));
    s.append(result_record(N, 0, fabricated(0)));
    auto r0 = fabricated(0), r1 = fabricated(2),
         r2 = fabricated(3);  // complete, time_limit, failed
    if (with_fields) {
        r0.fields = piece(engine::FieldKernel::cell, 11, 95);
        r1.fields = piece(engine::FieldKernel::cell, 22, 57);
        r2.fields = piece(engine::FieldKernel::cell, 33, 40);
    }
    s.append(result_record(F, 0, r0));
    s.append(result_record(F, 1, r1));
    s.append(result_record(F, 2, r2));
    s.end_run(store::RunEndRecord{store::utc_now(), "complete", 4, 1.0, 0.01});
    return path;
}

TEST(AnalyzeFields, StoreGroupEqualsTheMergedPiecesAndOneAccumulator) {
    const auto path = fields_store(true);
    std::ostringstream out, err, json;
    ASSERT_EQ(analyze_store(path, false, true, out, err), 0) << err.str();
    EXPECT_NE(out.str().find("fields per point"), std::string::npos) << out.str();
    const std::string group = "analysis/fields/" + F.label;
    const auto members = store::derived_group_members(path, "analysis/fields");
    EXPECT_EQ(members, (std::vector<std::string>{F.label, "labels"}));  // not N
    engine::FieldMoments direct = piece(engine::FieldKernel::cell, 11, 95);
    direct.merge(piece(engine::FieldKernel::cell, 22, 57));
    const engine::FieldMoments single = one_accumulator(engine::FieldKernel::cell, 95, 57);
    const auto& g = direct.grid;
    const std::vector<std::uint64_t> shape = {std::uint64_t(g.ny), std::uint64_t(g.nx)};
    const auto windows = store::read_derived_dataset(path, group + "/windows");
    EXPECT_EQ(windows.shape, shape);
    EXPECT_EQ(std::get<std::vector<std::int64_t>>(windows.values), direct.windows);
    EXPECT_EQ(std::get<std::vector<std::int64_t>>(windows.values), single.windows);
    const auto weight = store::read_derived_dataset(path, group + "/weight");
    for (int f = 0; f < engine::field_count; ++f) {
        const auto field = static_cast<engine::Field>(f);
        const std::string name(engine::field_name(field));
        const auto mean = store::read_derived_dataset(path, group + "/mean_" + name);
        const auto sd = store::read_derived_dataset(path, group + "/std_" + name);
        EXPECT_EQ(mean.shape, shape);
        EXPECT_EQ(sd.shape, shape);
        EXPECT_EQ(mean.units, engine::field_unit(field));
        EXPECT_EQ(sd.units, engine::field_unit(field));
        const auto& mv = std::get<std::vector<double>>(mean.values);
        const auto& sv = std::get<std::vector<double>>(sd.values);
        for (int c = 0; c < g.size(); ++c) {
            const bool data = direct.windows[c] > 0;
            for (const engine::FieldMoments* m : {&std::as_const(direct), &single}) {
                expect_near(mv[c], data ? m->mean[f][c] : 0.0, "mean_" + name);
                expect_near(sv[c], data ? m->fluctuation(field, c) : 0.0, "std_" + name);
                expect_near(std::get<std::vector<double>>(weight.values)[c], m->weight[c],
                            "weight");
            }
            if (direct.windows[c] < 2) {
                EXPECT_EQ(sv[c], 0.0);
            }
        }
    }
    const auto x = store::read_derived_dataset(path, group + "/x");
    EXPECT_EQ(x.units, "m");
    EXPECT_DOUBLE_EQ(std::get<std::vector<double>>(x.values).front(), g.x0 + 0.5 * g.cell);
    // JSON: the point with fields has a summary, the other none.
    ASSERT_EQ(analyze_store(path, true, false, json, err), 0);
    const auto parsed = nlohmann::ordered_json::parse(json.str());
    int with_summary = 0;
    for (const auto& p : parsed["points"]) {
        if (!p.contains("fields") || !p["fields"].is_object()) continue;
        ++with_summary;
        const auto& f = p["fields"];
        ASSERT_GE(f.size(), 2u) << json.str();
        EXPECT_EQ(f.begin().key(), "realizations");
        EXPECT_EQ(f["realizations"], 2);
        EXPECT_EQ(std::next(f.begin()).key(), "kernel");
        EXPECT_EQ(f["kernel"], "cell");
    }
    EXPECT_EQ(with_summary, 1) << json.str();
}

TEST(AnalyzeFields, StoreWithoutFieldsHasNoFieldData) {
    const auto path = fields_store(false);
    std::ostringstream out, err;
    ASSERT_EQ(analyze_store(path, false, true, out, err), 0) << err.str();
    const auto analysis = store::derived_group_members(path, "analysis");
    EXPECT_FALSE(analysis.empty());
    EXPECT_EQ(std::count(analysis.begin(), analysis.end(), "fields"), 0);
    EXPECT_TRUE(store::derived_group_members(path, "fields").empty());
    // Point F's scene asks for fields, but no realization has them: said, not invented.
    EXPECT_NE(out.str().find("no fields: no stored realization has fields"), std::string::npos)
        << out.str();
}

}  // namespace
}  // namespace hopper::analysis

namespace hopper::analysis {
namespace {

using cli::analyze_store;

// Issue 14, item 3: stores holding bit-identical realizations in different orders (one thread
// versus three ranks, or after a kill and resume) gave different gof_p and last-bit different
// means. Twelve realizations with jams, rates and fields, analysed in realization order and in
// a shuffled storage order: the JSON must be the same byte for byte.
std::vector<RealizationResult> varied_realizations(int n) {
    std::vector<RealizationResult> rs;
    std::mt19937_64 gen(2024);
    auto uniform = [&gen] { return static_cast<double>(gen() >> 11) * 0x1.0p-53; };
    for (int i = 0; i < n; ++i) {
        std::vector<double> t;
        for (int k = 0; k < 1 + i % 4; ++k)
            t.push_back(-0.7 * std::log(1.0 - uniform()));
        RealizationResult r = result(i % 3 ? Status::complete : Status::time_limit, t);
        r.discharge_rate = 40.0 + 10.0 * uniform();
        r.discharge_rate_mass = 0.01 * *r.discharge_rate + 1e-3 * uniform();
        r.fields = piece(engine::FieldKernel::cell, 11 + static_cast<std::uint64_t>(i), 20 + 3 * i);
        rs.push_back(std::move(r));
    }
    return rs;
}

const std::vector<int> storage_order = {5, 0, 11, 3, 8, 1, 10, 2, 7, 4, 9, 6};

TEST(AnalyzeOrder, JsonIsTheSameWhateverOrderTheRealizationsWereStoredIn) {
    const auto rs = varied_realizations(12);
    AnalysisPointInput ordered = point(3.0, 60, rs);
    AnalysisPointInput shuffled = point(3.0, 60, {});
    shuffled.planned = 12;
    for (int k = 0; k < 12; ++k) {
        ordered.realizations.push_back(k);
        ordered.rows.push_back(k);
        shuffled.results.push_back(rs[static_cast<std::size_t>(storage_order[k])]);
        shuffled.realizations.push_back(storage_order[k]);
        shuffled.rows.push_back(k);
    }
    const Analysis a = analyze_points({ordered}), b = analyze_points({shuffled});
    ASSERT_TRUE(a.points[0].gof.valid) << "the bootstrap must be part of the comparison";
    ASSERT_TRUE(a.points[0].fields.merged.has_value());
    EXPECT_EQ(analysis_json(a, "s.h5", "c"), analysis_json(b, "s.h5", "c"));
    EXPECT_EQ(a.points[0].gof.p_value, b.points[0].gof.p_value);
    EXPECT_EQ(a.points[0].rate.mean, b.points[0].rate.mean);
}

// What read_inputs drops from each result as it reads a store (keep_what_analysis_reads, issue
// 44) changes nothing: the same realizations with everything filled in (exit times, curves,
// events with restarts, arches with centres, diagnostics, a message) give the same JSON, slimmed
// or whole. The fixture's events and arches take part: dropping them does change it.
TEST(AnalyzeSlim, WhatTheAnalysisDoesNotReadIsDroppedWithoutChangingABit) {
    auto rs = varied_realizations(12);
    for (std::size_t i = 0; i < rs.size(); ++i) {
        auto& r = rs[i];
        double at = 0.0;
        for (std::size_t k = 0; k < r.survival_times.size(); ++k) {
            at += r.survival_times[k];
            r.avalanche_sizes.push_back(static_cast<int>(10 + 7 * k + i));
            r.exit_times.push_back(at);
            r.curve_time.push_back(at);
            r.curve_count.push_back(static_cast<int>(100 - k));
            if (!r.censored[k]) {
                // The flow restarts a while after each onset: the early/late test's input.
                r.events.push_back({engine::Event::Kind::jam, at, at, 50});
                r.events.push_back(
                    {engine::Event::Kind::flow_restart, at + 0.05 * double(1 + i % 3), at, 50});
                engine::Arch a;
                for (std::size_t d = 0; d < 3 + i % 3; ++d) {
                    a.ids.push_back(static_cast<int>(d));
                    a.x.push_back(0.001 * double(d));
                    a.y.push_back(0.002);
                }
                a.span = 0.02 + 0.001 * double(i);
                a.max_angle = 2.5;
                r.arches.push_back(a);
            }
        }
        r.message = "a message the analysis does not show";
        r.diagnostics.steps = 1000 + static_cast<std::int64_t>(i);
        r.diagnostics.force_path = "reference";
    }
    auto slim = rs;
    for (auto& r : slim)
        keep_what_analysis_reads(r);
    EXPECT_TRUE(slim[1].exit_times.empty() && slim[1].curve_time.empty() &&
                slim[1].arches.at(0).x.empty() && slim[1].diagnostics.steps == 0);
    const auto json = [](std::vector<RealizationResult> r) {
        return analysis_json(analyze_points({point(3.0, 60, std::move(r))}), "s.h5", "c");
    };
    const std::string whole = json(rs);
    EXPECT_EQ(json(slim), whole);
    // Teeth: the fixture's events (the early/late test) and arches (sizes, spans) are read.
    auto no_events = slim, no_arches = slim;
    for (auto& r : no_events)
        r.events.clear();
    for (auto& r : no_arches)
        r.arches.clear();
    EXPECT_NE(json(no_events), whole);
    EXPECT_NE(json(no_arches), whole);
}

// The same through the store: two stores at the same path, filled in two orders, give the same
// `campaign analyze --json` text.
TEST(AnalyzeOrder, StoresFilledInDifferentOrdersAnalyseByteForByteTheSame) {
    const auto rs = varied_realizations(12);
    store::PointPlan P = store::testing::point(
        "D_cm=3 theta_deg=60", 12,
        "particles.d_large_m=0.0077\nparticles.density_kg_m3=1000\nparticles.thickness_m=0.003\n"
        "fields.window_s=0.01\nfields.kernel=cell\n");
    P.settings = {{"D_cm", 3.0}, {"theta_deg", 60.0}};
    P.parameters = {{"hopper.d_large_cm", 0.77},
                    {"hopper.density_kg_m3", 1000.0},
                    {"hopper.thickness_cm", 0.3},
                    {"fields.enabled", std::string("true")}};
    const auto dir = store::testing::scratch();
    auto analyse = [&](const std::vector<int>& order) {
        const auto path = dir / "s.h5";
        std::filesystem::remove(path);
        std::filesystem::remove(store::journal_path(path));
        {
            store::Store s(path);
            s.begin_run(store::testing::run_record({P}));
            for (int i : order)
                s.append(store::testing::result_record(P, i, rs[static_cast<std::size_t>(i)],
                                                       1 + i % 2));
            s.end_run(store::RunEndRecord{store::utc_now(), "complete", 12, 1.0, 0.01});
        }
        std::ostringstream out, err;
        EXPECT_EQ(analyze_store(path, true, false, out, err), 0) << err.str();
        return out.str();
    };
    std::vector<int> ascending(12);
    std::iota(ascending.begin(), ascending.end(), 0);
    const std::string a = analyse(ascending), b = analyse(storage_order);
    ASSERT_NE(a.find("\"gof_p\": 0."), std::string::npos) << a;
    EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace hopper::analysis
