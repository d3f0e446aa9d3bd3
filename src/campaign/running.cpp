#include "hopper/campaign/running.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>

namespace hopper::campaign {

namespace fs = std::filesystem;

fs::path running_path(const fs::path& store) {
    fs::path p = store;
    p += ".running";
    return p;
}

void write_running(const fs::path& path, const RunningFile& f) {
    fs::path tmp = path;
    tmp += ".tmp";
    {
        std::ofstream out(tmp, std::ios::trunc);
        if (!out) return;
        char t[64];
        std::snprintf(t, sizeof t, "%.3f", f.updated_unix);
        out << "hopper-running 1\nmaster\t" << f.pid << '\t' << f.host << '\t' << t << '\n';
        for (const RunningTask& r : f.tasks) {
            std::snprintf(t, sizeof t, "%.3f", r.start_unix);
            out << "task\t" << r.worker << '\t' << t << '\t' << r.attempt << '\t'
                << (r.resumed ? 1 : 0) << '\t' << r.realization << '\t' << r.label << '\n';
        }
        if (!out.flush()) return;
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
}

std::optional<RunningFile> read_running(const fs::path& path) {
    std::ifstream in(path);
    if (!in) return std::nullopt;
    std::string line;
    if (!std::getline(in, line) || line != "hopper-running 1") return std::nullopt;
    RunningFile f;
    if (!std::getline(in, line)) return std::nullopt;
    {
        std::istringstream ls(line);
        std::string word;
        if (!std::getline(ls, word, '\t') || word != "master") return std::nullopt;
        std::string pid, updated;
        if (!std::getline(ls, pid, '\t') || !std::getline(ls, f.host, '\t') ||
            !std::getline(ls, updated))
            return std::nullopt;
        try {
            f.pid = std::stoll(pid);
            f.updated_unix = std::stod(updated);
        } catch (...) {
            return std::nullopt;
        }
    }
    while (std::getline(in, line)) {
        std::istringstream ls(line);
        std::string word, worker, start, attempt, resumed, realization;
        RunningTask t;
        if (!std::getline(ls, word, '\t') || word != "task" || !std::getline(ls, worker, '\t') ||
            !std::getline(ls, start, '\t') || !std::getline(ls, attempt, '\t') ||
            !std::getline(ls, resumed, '\t') || !std::getline(ls, realization, '\t') ||
            !std::getline(ls, t.label))
            return std::nullopt;
        try {
            t.worker = std::stoi(worker);
            t.start_unix = std::stod(start);
            t.attempt = std::stoi(attempt);
            t.resumed = resumed == "1";
            t.realization = std::stoi(realization);
        } catch (...) {
            return std::nullopt;
        }
        f.tasks.push_back(std::move(t));
    }
    return f;
}

}  // namespace hopper::campaign
