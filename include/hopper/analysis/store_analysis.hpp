#pragma once
// A store's analysis: its plan with typed settings (campaign::read_plan) and its realizations
// (the journal, through store::read_journal_realizations) -> the points' inputs -> the
// statistics and their JSON; and the /analysis group written back into the store. `campaign
// analyze` and the end of `campaign run` (RunOptions::after_run) use it.

#include <filesystem>
#include <string>
#include <vector>

#include "hopper/analysis/analyze.hpp"

namespace hopper::analysis {

struct StoreInputs {
    std::string campaign;                    // the campaign's name
    std::vector<AnalysisPointInput> points;  // every planned point, in the order it entered
};

// Every point the store was ever asked for with its stored realizations (each with its
// realization index). Throws core::StoreError when there is no store.
StoreInputs read_inputs(const std::filesystem::path& store);

struct StoreAnalysis {
    std::string campaign;
    Analysis analysis;
    std::string json;  // analysis_json(analysis, store as given, campaign)
};

StoreAnalysis analyze_store(const std::filesystem::path& store);

// Replaces the store's /analysis group (store::write_derived_group: refused while a run holds
// the store; throws core::StoreError).
void write_analysis_group(const std::filesystem::path& store, const StoreAnalysis& a);

}  // namespace hopper::analysis
