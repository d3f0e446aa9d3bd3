#pragma once
// Which realization each worker runs, for `campaign status` during a run (issue 16): the master
// replaces a small text file beside the store, STORE.running, whenever a task is handed out or
// ends (written to a temporary name and renamed, so a reader sees the old or the new file,
// never half of one), and removes it when the run ends. A file left by a killed run names its
// master's pid and host, so status can tell it is stale.
//
// Format (text, tab-separated):
//   hopper-running 1
//   master <pid> <host> <updated, s since 1970>
//   task <worker> <start, s since 1970> <attempt> <resumed 0|1> <realization> <label>
//   ... one task line per running realization

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace hopper::campaign {

struct RunningTask {
    int worker = 0;
    double start_unix = 0.0;
    int attempt = 1;
    bool resumed = false;  // continued from a checkpoint
    int realization = 0;
    std::string label;
};

struct RunningFile {
    std::int64_t pid = 0;
    std::string host;
    double updated_unix = 0.0;
    std::vector<RunningTask> tasks;
};

std::filesystem::path running_path(const std::filesystem::path& store);
// Best effort: the run goes on when the file cannot be written (status then shows less).
void write_running(const std::filesystem::path& path, const RunningFile& f);
// nullopt when there is no file or it cannot be read as one.
std::optional<RunningFile> read_running(const std::filesystem::path& path);

}  // namespace hopper::campaign
