#pragma once
// `campaign plot` and `campaign export`: thin front ends of the Python tools in analysis/
// (plots.py, export.py), run with the system interpreter (/usr/bin/python3, Debian's h5py, numpy,
// pandas, xarray and matplotlib). The C++ side checks the arguments it can (the store exists, the
// formats are known), then runs the script with the same arguments and returns its exit code.
//
// Where: the analysis directory of the source tree this binary was built from, or
// $HOPPER_ANALYSIS_DIR; the interpreter $HOPPER_PYTHON or /usr/bin/python3.
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace hopper::cli {

void print_plot_help(std::ostream& os);
void print_export_help(std::ostream& os);
int plot_command(const std::vector<std::string>& args);
int export_command(const std::vector<std::string>& args);

// The analysis directory and the interpreter (after the environment overrides).
std::filesystem::path analysis_dir();
std::filesystem::path python_interpreter();

// Runs `python script args...` and waits; returns its exit code (1 when it could not start or
// was killed, with a message on stderr).
int run_python(const std::filesystem::path& script, const std::vector<std::string>& args);

// Checks a --format list ("png,pdf,svg"): each of png, pdf, svg, once. Throws core::ConfigError
// naming the bad entry and what is allowed.
std::vector<std::string> parse_formats(const std::string& text);

}  // namespace hopper::cli
