#pragma once
// `campaign analyze STORE [--json]`: the options and the printing. The statistics, their JSON
// and the /analysis group are the analysis layer's (hopper/analysis); this prints them as tables
// (or the JSON object) and asks the layer to write /analysis. `campaign run` calls
// analyze_store() at the end of a run (RunOptions::after_run).

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "hopper/analysis/analyze.hpp"

namespace hopper::cli {

// The tables.
void write_analysis(std::ostream& out, const analysis::Analysis& a);

// Reads the store (its journal: the source of truth), analyzes it, prints tables (or JSON) on
// `out`, and when `write` replaces /analysis in the HDF5 file (then *written, if given, says
// whether it was). Returns the exit code.
int analyze_store(const std::filesystem::path& store, bool json, bool write, std::ostream& out,
                  std::ostream& err, bool* written = nullptr);

void print_analyze_help(std::ostream& os);
int analyze_command(const std::vector<std::string>& args);

}  // namespace hopper::cli
