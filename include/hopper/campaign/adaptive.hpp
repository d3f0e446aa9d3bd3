#pragma once
// Campaigns that stop when good enough (issue 13): with a [campaign] target, realizations run in
// rounds. The first round gives every point its `realizations`; after a complete round, each
// point's precision is computed from its results so far (the relative half-width of the 95 %
// chi-square interval of tau, or of the mean avalanche size <s>), and every point that has not
// met the target and has fewer than max_realizations gets round_realizations more. The run ends
// when no point needs more.
//
// Determinism: a point's round k consists of realization indices fixed by the decisions before
// it, and a decision uses only the results of complete rounds (indices below the point's
// allotment), which are the same whatever the rank count. The decisions are not stored: they
// are replayed from the stored results (replay_rounds), so a resume, after any interruption,
// continues exactly the same sequence of rounds. Within a round, points are handed out cheapest
// information first: ascending expected cost of the realizations the point still needs.

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "hopper/config/sweep.hpp"
#include "hopper/engine/result.hpp"

namespace hopper::campaign {

// Results of one point by realization index (any status).
using PointResults = std::map<int, engine::RealizationResult>;

struct PointPrecision {
    int used = 0;  // realizations in the statistic (not failed)
    int jams = 0;  // r
    bool has_estimate = false;
    double estimate = 0.0;        // tau (s) or <s> (grains)
    double rel_half_width = 0.0;  // (hi - lo) / (2 estimate); valid when has_estimate
};

// The precision of `quantity` from the results with index < n (failed ones left out).
PointPrecision precision(const PointResults& results, int n,
                         config::CampaignTarget::Quantity quantity);

struct PointRounds {
    std::string label;
    int allotted = 0;  // realization indices [0, allotted) belong to the rounds so far
    bool done = false;
    std::string why;           // why it stopped (done) or why it needs more
    PointPrecision precision;  // at the last decision
};

struct RoundState {
    int round = 0;                    // rounds decided so far (0: still in the first)
    std::vector<PointRounds> points;  // in the spec's order
    bool finished = false;            // every point done: nothing more to run
    // The realizations of the current round still missing, cheapest information first:
    // (point index, realization index).
    std::vector<std::pair<int, int>> missing;
};

// Every stored result of a store's journal by point label and realization index, reduced to
// what precision() reads (status, survival intervals, censoring, avalanche sizes): the rounds are
// replayed from the whole journal at every round, so the results are read one at a time and
// slimmed as they come (issue 44; a whole result of the tiny scene is about 15 kB).
std::map<std::string, PointResults> read_round_results(const std::filesystem::path& store);

// Replays the decisions from the stored results (by point label) and returns where the
// campaign stands: the current round and what it still lacks, or finished. `cost` is the
// expected cost of one realization per point (for the order within a round).
RoundState replay_rounds(const config::CampaignSpec& spec,
                         const std::map<std::string, PointResults>& stored,
                         const std::vector<double>& cost);

// One line per point: label, realizations, jams, estimate and relative half-width, why.
std::string describe_rounds(const RoundState& s, config::CampaignTarget::Quantity quantity);

}  // namespace hopper::campaign
