// The `campaign` executable: hands the command line to the command table (commands.hpp), which
// dispatches to a command; the commands are in src/cli/<command>.cpp and the exit codes in
// exit_codes.hpp.

#include <string>
#include <vector>

#include "cli/commands.hpp"

int main(int argc, char** argv) {
    return hopper::cli::dispatch(std::vector<std::string>(argv + 1, argv + argc));
}
