#pragma once
// The statistics of issue 4 per point and across points, from a store's realizations (no I/O):
// survival times (censored exponential MLE, goodness of fit, Kaplan–Meier, early/late jam
// rates), empty times, flow rates, avalanche sizes and arches, merged coarse-grained fields, and
// per group of points (the wall angle and the other varied settings) the Beverloo fit and the
// fits of the jam rate and of <s> versus the outlet D. The numbers come from hopper::stats; this
// layer gathers the realizations per point, calls the fits and keeps what they return. A value
// that cannot be computed is absent with a reason, never a made-up number.
//
// Settings are typed (core::Setting, from the store's plan): the outlet, the angle, the varied
// settings and the scene parameters (density, thickness, diameters) are read from them, never
// from labels or scene texts.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hopper/core/setting.hpp"
#include "hopper/engine/result.hpp"
#include "hopper/stats/beverloo.hpp"
#include "hopper/stats/exponential_fit.hpp"
#include "hopper/stats/gof.hpp"
#include "hopper/stats/jam_rate_fit.hpp"
#include "hopper/stats/kaplan_meier.hpp"
#include "hopper/stats/summary.hpp"
#include "hopper/stats/time_dependence.hpp"

namespace hopper::analysis {

// Packing fraction assumed for the 2D bulk density (the settled packing's area is not stored).
inline constexpr double kAssumedPackingFraction = 0.82;

// One point as the analysis sees it.
struct AnalysisPointInput {
    std::string label;  // "D_cm=3 theta_deg=60"
    // The label's settings (D_cm, theta_deg, then the other varied ones) and every scene
    // parameter, typed, under the sweep file's names and units (store::PointPlan).
    std::vector<core::Setting> settings;
    std::vector<core::Setting> parameters;
    // The outlet and angle when `settings` lacks them (a point of an old store whose sweep text
    // could not be read back: the plan's SI round trip).
    double D_cm = 0.0, theta_deg = 0.0;
    int planned = 0;                                 // realizations planned
    std::vector<engine::RealizationResult> results;  // stored realizations (any status)
    // The row in /realizations of each result (same order); empty: rows unknown (messages then
    // name the realization index, or the index in `results`).
    std::vector<std::int64_t> rows;
    // The realization index of each result (same order). When given, analyze_points() uses the
    // results in ascending index, so that every statistic (sums, the bootstrap, the field merge)
    // is the same whatever order the realizations were stored in (rank count, resumes).
    std::vector<int> realizations;
};

// `in` with its results (and rows) in ascending realization index; unchanged when the indices
// are not given. Stable: equal indices keep their order.
AnalysisPointInput in_realization_order(AnalysisPointInput in);

// Drops from `r` what analyze_points never reads: the exit times, the discharge curve, the
// arches' centres (their disks' ids stay: the sizes), the shakes per jam, the message and the
// diagnostics. read_inputs applies it to each result as the journal is read, so that a store's
// inputs take about what the statistics need (issue 44: 15 kB per realization of the tiny
// scene before, every result held whole). The analysis of the slimmed results is the same to
// the bit (tested).
void keep_what_analysis_reads(engine::RealizationResult& r);

// The nodes of merged fields with at least one window, and the largest mean speed (m/s) and
// mean pressure (m g) over them (0 when there are none).
struct FieldsSummary {
    std::int64_t cells_with_data = 0;
    double max_mean_speed = 0.0;
    double max_mean_pressure = 0.0;
};
FieldsSummary summarize(const engine::FieldMoments& m);

// A point's coarse-grained fields (issue 7): the pieces of its realizations that did not fail,
// merged exactly (engine::FieldMoments::merge, in the order of `results`: analyze_points() puts
// them in realization order first).
struct PointFields {
    bool enabled = false;  // the point's scene samples fields, or a result has them
    std::optional<engine::FieldMoments> merged;  // absent: see reason
    std::string reason;    // why merged is absent ("no realization without failure has ...")
    bool error = false;    // the reason is an inconsistency (grids differ inside the point)
    int realizations = 0;  // realizations merged
    std::int64_t cells_with_data = 0;  // nodes with at least one window
    double max_mean_speed = 0.0;       // m/s, over the nodes with data
    double max_mean_pressure = 0.0;    // m g
};

// Merges the fields of the realizations of `in` that did not fail. Throws core::StoreError naming
// the point and the rows (or realizations) when two pieces have different grids.
PointFields merge_point_fields(const AnalysisPointInput& in);

// Avalanche sizes and arches of one point (issue 13; docs/statistics.md, "Avalanches").
struct AvalancheAnalysis {
    int realizations = 0;          // used realizations with avalanche sizes
    int realizations_without = 0;  // used realizations stored before avalanche sizes existed
    // The censored exponential fit on the sizes: tau is <s> (grains per avalanche), T the
    // grains that passed, r the jams; 1/<s> is the clogging probability per grain.
    std::optional<stats::ExponentialFit> fit;
    std::string reason;  // why fit or <s> is missing
    stats::GofResult gof;
    int arch_jams = 0;                           // jams with arch data
    int arches_found = 0;                        // of them, with an arch
    std::vector<std::int64_t> arch_size_counts;  // [n]: arches of n disks
    std::optional<double> arch_mean_size, arch_mean_span_m, arch_mean_max_angle_deg;
};

struct PointAnalysis {
    std::string label;
    double D_cm = 0.0, theta_deg = 0.0;
    std::vector<core::Setting> varied;  // label settings besides D, theta
    std::string group;  // theta and the other varied settings: the points of one Beverloo fit
    int planned = 0, stored = 0;
    int n_complete = 0, n_failed = 0, n_arrested = 0, n_time_limit = 0;
    int used = 0;  // realizations in the statistics (not failed)
    int n_jams = 0, n_shakes = 0, n_jams_multi_shake = 0;
    std::optional<stats::ExponentialFit> fit;  // absent: no survival intervals
    std::string fit_reason;
    stats::GofResult gof;
    stats::LogSurvivalLine line;
    stats::KaplanMeierCurve km;
    stats::EarlyLateTest early_late;
    stats::SampleSummary empty_time, rate, rate_kg;
    double rho_b = 0.0, d_mean = 0.0;  // kg/m^2 (estimate), m
    PointFields fields;
    AvalancheAnalysis avalanche;
};

struct GroupAnalysis {
    std::string group;
    double theta_deg = 0.0;
    std::vector<int> points;  // indices into Analysis::points
    stats::BeverlooFit beverloo;
    stats::JamRateFits jam_rate;
    std::vector<std::pair<double, std::string>> jam_rate_left_out;  // D_cm, reason
    // <s>(D): fitted as the clogging probability per grain p = 1/<s> with the jam-rate laws, so
    // exponential: <s> = exp(-ln A) exp(B D); power law: <s> = exp(-ln A) (Dc - D)^-gamma.
    stats::JamRateFits avalanche;
    std::vector<std::pair<double, std::string>> avalanche_left_out;  // D_cm, reason
};

struct Analysis {
    std::vector<PointAnalysis> points;
    std::vector<GroupAnalysis> groups;
    std::string rho_b_source, d_definition;
};

// Statistics of the given points.
Analysis analyze_points(const std::vector<AnalysisPointInput>& points);

}  // namespace hopper::analysis
