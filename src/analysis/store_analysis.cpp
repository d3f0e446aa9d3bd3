#include "hopper/analysis/store_analysis.hpp"

#include <map>

#include "hopper/analysis/derived.hpp"
#include "hopper/analysis/json.hpp"
#include "hopper/campaign/plan.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/store.hpp"

namespace hopper::analysis {

namespace fs = std::filesystem;

StoreInputs read_inputs(const fs::path& store) {
    std::error_code ec;
    const fs::path journal = store::journal_path(store);
    const bool journal_exists = fs::exists(journal, ec);
    if (ec)
        throw core::StoreError("cannot access the store's journal '" + journal.string() +
                               "': " + ec.message());
    if (!journal_exists)
        throw core::StoreError("no store at '" + store.string() + "' (its journal '" +
                               journal.string() + "' does not exist)");
    const store::CampaignPlan plan = campaign::read_plan(store);
    StoreInputs out;
    out.campaign = plan.name;
    std::map<std::string, std::size_t> index;
    for (const auto& p : plan.points) {
        index[p.label] = out.points.size();
        AnalysisPointInput in;
        in.label = p.label;
        in.settings = p.settings;
        in.parameters = p.parameters;
        in.D_cm = p.D_cm;
        in.theta_deg = p.theta_deg;
        in.planned = p.realizations();
        out.points.push_back(std::move(in));
    }
    // Each result with its realization index, reduced to what the statistics read as it comes
    // (one decoded result at a time in memory), then each point in realization order:
    // analyze_points uses that order, so nothing depends on the order the journal holds them in,
    // and it finds them ordered (no copy of a point's results).
    store::for_each_journal_realization(store, [&](store::StoredRealization&& r) {
        const auto it = index.find(r.label);
        if (it == index.end()) return;
        auto& in = out.points[it->second];
        keep_what_analysis_reads(r.result);
        in.results.push_back(std::move(r.result));
        in.realizations.push_back(r.record.realization);
    });
    for (auto& in : out.points)
        in = in_realization_order(std::move(in));
    return out;
}

StoreAnalysis analyze_store(const fs::path& store) {
    StoreInputs inputs = read_inputs(store);
    StoreAnalysis out;
    out.campaign = std::move(inputs.campaign);
    out.analysis = analyze_points(inputs.points);
    out.json = analysis_json(out.analysis, store.string(), out.campaign);
    return out;
}

void write_analysis_group(const fs::path& store, const StoreAnalysis& a) {
    store::write_derived_group(store, analysis_group(a.analysis, a.json));
}

}  // namespace hopper::analysis
