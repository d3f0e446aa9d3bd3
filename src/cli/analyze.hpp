#pragma once
// `campaign analyze STORE [--json]`: the statistics of issue 4 for every point of a store and
// across points, printed as tables (or one JSON object) and written into the store's /analysis
// group (replaced on re-analysis). `campaign run` calls analyze_store() at the end of a run.
//
// The numbers come from hopper::stats; this file only gathers the realizations per point,
// calls the fits and formats what they return. A value that cannot be computed is JSON null with
// a `<key>_reason`, never a made-up number.

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "hopper/engine/result.hpp"
#include "hopper/stats/beverloo.hpp"
#include "hopper/stats/exponential_fit.hpp"
#include "hopper/stats/gof.hpp"
#include "hopper/stats/jam_rate_fit.hpp"
#include "hopper/stats/kaplan_meier.hpp"
#include "hopper/stats/summary.hpp"
#include "hopper/stats/time_dependence.hpp"
#include "hopper/store/analysis.hpp"

namespace hopper::cli {

// Packing fraction assumed for the 2D bulk density (the settled packing's area is not stored).
inline constexpr double kAssumedPackingFraction = 0.82;

// One point as the analysis sees it.
struct AnalysisPointInput {
    std::string label;                         // "D_cm=3 theta_deg=60"
    std::map<std::string, std::string> scene;  // every scene parameter, name -> value (SI)
    double D_cm = 0.0, theta_deg = 0.0;
    int planned = 0;                                 // realizations planned
    std::vector<engine::RealizationResult> results;  // stored realizations (any status)
    // The row in /realizations of each result (same order); empty: rows unknown (messages then
    // give the index in `results`).
    std::vector<std::int64_t> rows;
    // The realization index of each result (same order). When given, analyze_points() uses the
    // results in ascending index, so that every statistic (sums, the bootstrap, the field merge)
    // is the same whatever order the realizations were stored in (rank count, resumes).
    std::vector<int> realizations;
};

// `in` with its results (and rows) in ascending realization index; unchanged when the indices
// are not given. Stable: equal indices keep their order.
AnalysisPointInput in_realization_order(AnalysisPointInput in);

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
// the point and the rows when two pieces have different grids.
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
    std::vector<std::pair<std::string, std::string>> varied;  // label settings besides D, theta
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

// The pure part: statistics of the given points (no I/O).
Analysis analyze_points(const std::vector<AnalysisPointInput>& points);
// The JSON object of `campaign analyze --json`.
std::string analysis_json(const Analysis& a, const std::string& store, const std::string& name);
// The /analysis group (datasets per point, the Kaplan–Meier curves, the fits).
store::DerivedGroup analysis_group(const Analysis& a, const std::string& json);
// The tables.
void write_analysis(std::ostream& out, const Analysis& a);

// Reads the store (its journal: the source of truth), analyzes it, prints tables (or JSON) on
// `out`, and when `write` replaces /analysis in the HDF5 file. Returns the exit code.
int analyze_store(const std::filesystem::path& store, bool json, bool write, std::ostream& out,
                  std::ostream& err);

void print_analyze_help(std::ostream& os);
int analyze_command(const std::vector<std::string>& args);

}  // namespace hopper::cli
