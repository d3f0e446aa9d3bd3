// The `campaign` executable: hands the command line to the command table (commands.hpp), which
// dispatches to a command; the commands are in src/cli/<command>.cpp and the exit codes in
// exit_codes.hpp.

#include <csignal>
#include <string>
#include <vector>

#include "cli/commands.hpp"

int main(int argc, char** argv) {
    // `campaign run` under Slurm: the warning SIGUSR1 can come as the allocation starts, before
    // the master catches it (a drain); until then it is ignored rather than fatal (its default
    // action), on every rank (issue 29, item 9).
    if (argc > 1 && std::string(argv[1]) == "run") std::signal(SIGUSR1, SIG_IGN);
    return hopper::cli::dispatch(std::vector<std::string>(argv + 1, argv + argc));
}
