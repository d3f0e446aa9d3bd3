#pragma once
// The exit codes of the `campaign` executable, in one place: the enum the commands return and
// the table `campaign --help` prints. The two codes `campaign run` itself produces are the
// campaign layer's (campaign::RunExit, run.hpp: the library returns them, so the numbers are
// written there) and named here with the others.

#include <string_view>

#include "hopper/campaign/run.hpp"

namespace hopper::cli {

enum ExitCode : int {
    exit_ok = campaign::run_ok,
    exit_error = 1,  // an unexpected failure (I/O, store, internal error)
    exit_usage = 2,  // bad command line or sweep file, or a store refused (core::ConfigError)
    // simulate: the realization ended with status failed; run: some realizations failed.
    exit_realization_failed = campaign::run_with_failures,
    exit_stopped = campaign::run_stopped,  // run: stopped by a signal; the same command resumes
    // run: every realization is stored (the journal), but the analysis at its end could not be
    // written into the store (a full disk); `campaign analyze STORE` writes it (issue 29).
    exit_analysis_not_written = 5,
};

struct ExitCodeMeaning {
    ExitCode code;
    std::string_view meaning;
};

// What `campaign --help` lists; each command's own help says what the codes mean for it.
inline constexpr ExitCodeMeaning exit_code_meanings[] = {
    {exit_ok, "success"},
    {exit_error, "unexpected or store error"},
    {exit_usage, "bad command line or sweep file"},
    {exit_realization_failed, "realization(s) failed"},
    {exit_stopped, "stopped by a signal (run; resumable)"},
    {exit_analysis_not_written, "realizations stored, analysis not written (run; disk full?)"},
};

}  // namespace hopper::cli
