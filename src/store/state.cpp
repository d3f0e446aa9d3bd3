#include "state.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <algorithm>

#include "hopper/core/error.hpp"

namespace hopper::store {

std::string to_string(TaskState s) {
    switch (s) {
        case TaskState::pending:
            return "pending";
        case TaskState::done:
            return "done";
        case TaskState::failed:
            return "failed";
        case TaskState::error:
            return "error";
    }
    return "?";
}

ResultSummary summarize(const engine::RealizationResult& r, const ResultRecord& rec) {
    ResultSummary s;
    s.status = r.status;
    s.n_jams = r.n_jams;
    s.n_intervals = static_cast<int>(r.survival_times.size());
    for (std::size_t i = 0; i < r.survival_times.size(); ++i) {
        s.survival_sum += r.survival_times[i];
        if (i < r.censored.size() && !r.censored[i]) ++s.n_uncensored;
    }
    s.empty_time = r.empty_time;
    s.rank = rec.rank;
    s.task_seconds = rec.task_seconds;
    return s;
}

bool State::closed_in_step() const {
    return last_type == RecordType::sync && last_sync && last_sync->journal_bytes == last_offset &&
           last_sync->rows == static_cast<std::uint64_t>(rows);
}

void fsync_path(const std::filesystem::path& p, bool directory) {
    const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC | (directory ? O_DIRECTORY : 0));
    if (fd < 0) return;
    ::fsync(fd);
    ::close(fd);
}

FileCheck check_closed_file(const State& state, const std::filesystem::path& path) {
    if (!state.closed_in_step() || !state.last_sync->file) return FileCheck::unrecorded;
    const FileChecksum& want = *state.last_sync->file;
    try {
        const FileChecksum now = checksum_file(path);
        if (now == want) return FileCheck::intact;
        return now.bytes == want.bytes ? FileCheck::changed : FileCheck::other;
    } catch (const core::StoreError&) {
        return FileCheck::other;
    }
}

int State::find_point(const std::string& label) const {
    const auto it = point_index.find(label);
    return it == point_index.end() ? -1 : it->second;
}

std::uint64_t State::seed_of(int point, int realization) const {
    const auto& seeds = plan.points[static_cast<std::size_t>(point)].seeds;
    return realization < static_cast<int>(seeds.size())
               ? seeds[static_cast<std::size_t>(realization)]
               : 0;
}

bool State::extend_seeds(int point, int first, std::span<const std::uint64_t> seeds) {
    auto& mine = plan.points[static_cast<std::size_t>(point)];
    const std::size_t end = static_cast<std::size_t>(first) + seeds.size();
    if (static_cast<std::size_t>(first) > mine.seeds.size())
        throw core::StoreError("journal extends point '" + mine.label + "' from realization " +
                               std::to_string(first) + " but plans only " +
                               std::to_string(mine.seeds.size()) + " (damaged journal)");
    if (end <= mine.seeds.size()) return false;
    // Seeds depend only on (campaign seed, settings, index): the prefix is the same.
    const std::size_t have = mine.seeds.size() - static_cast<std::size_t>(first);
    mine.seeds.insert(mine.seeds.end(), seeds.begin() + static_cast<std::ptrdiff_t>(have),
                      seeds.end());
    mine.limit = std::max(mine.limit, mine.realizations());
    auto& t = tasks[static_cast<std::size_t>(point)];
    if (t.size() < mine.seeds.size()) t.resize(mine.seeds.size());
    return true;
}

bool State::apply(RunStartRecord&& r) {
    // The previous run died (no end record): what it was running died with it.
    if (!runs.empty() && !runs.back().end) {
        for (const auto& [p, r] : in_flight) {
            TaskEntry& e = tasks[static_cast<std::size_t>(p)][static_cast<std::size_t>(r)];
            if (e.deaths < 255) ++e.deaths;
        }
        runs.back().died_running = static_cast<int>(in_flight.size());
    }
    in_flight.clear();
    bool changed = false;
    if (plan.points.empty() && runs.empty()) plan.seed = r.plan.seed;
    plan.name = r.plan.name;
    for (auto& p : r.plan.points) {
        const int i = find_point(p.label);
        if (i < 0) {
            point_index[p.label] = static_cast<int>(plan.points.size());
            tasks.emplace_back(p.seeds.size());
            p.limit = p.max_realizations();
            plan.points.push_back(std::move(p));
            changed = true;
            continue;
        }
        auto& mine = plan.points[static_cast<std::size_t>(i)];
        if (p.max_realizations() > mine.limit) {
            mine.limit = p.max_realizations();
            changed = true;
        }
        if (extend_seeds(i, 0, p.seeds)) changed = true;
    }
    runs.push_back(RunSummary{std::move(r.run), std::nullopt, 0, 0, {}});
    return changed;
}

bool State::apply(const AllotmentRecord& r) {
    bool changed = false;
    for (const auto& p : r.points) {
        const int i = find_point(p.label);
        if (i < 0)
            throw core::StoreError("journal allots realizations to point '" + p.label +
                                   "', which no run planned (damaged journal)");
        if (extend_seeds(i, p.first, p.seeds)) changed = true;
    }
    return changed;
}

std::int64_t State::apply(const ResultRecord& r, const engine::RealizationResult& result) {
    const auto [p, entry] = entry_for(r.label, r.realization, "a result");
    TaskEntry& e = *entry;
    if (e.result) {
        ++duplicates;
        return -1;
    }
    e.result = summarize(result, r);
    e.state = result.status == engine::Status::failed ? TaskState::failed : TaskState::done;
    if (e.state == TaskState::failed) messages[{p, r.realization}].result = result.message;
    e.row = rows++;
    in_flight.erase({p, r.realization});
    if (!runs.empty()) {
        ++runs.back().stored;
        double& last = runs.back().last_result_unix[r.rank];
        last = std::max(last, r.finished_unix);
    }
    return e.row;
}

int State::apply(const ErrorRecord& r) {
    const auto [p, entry] = entry_for(r.label, r.realization, "an error");
    TaskEntry& e = *entry;
    ++e.errors;
    in_flight.erase({p, r.realization});
    messages[{p, r.realization}].last_error = r.reason;
    if (!e.result) e.state = TaskState::error;
    failures.push_back(Failure{r.label, r.realization, r.seed, r.rank, r.attempt, true, r.reason});
    return p;
}

void State::apply(const RunEndRecord& r) {
    if (!runs.empty()) runs.back().end = r;
    in_flight.clear();  // an ending run stopped its realizations itself: none died
}

void State::apply(const DispatchRecord& r) {
    in_flight.insert({entry_for(r.label, r.realization, "a dispatch").first, r.realization});
}

std::pair<int, TaskEntry*> State::entry_for(const std::string& label, int realization,
                                            const char* what) {
    const int p = find_point(label);
    if (p < 0)
        throw core::StoreError(std::string("journal holds ") + what + " for point '" + label +
                               "', which no run planned (damaged journal)");
    if (realization < 0)
        throw core::StoreError(std::string("journal holds ") + what +
                               " with a negative realization index");
    auto& t = tasks[static_cast<std::size_t>(p)];
    if (static_cast<std::size_t>(realization) >= t.size())
        t.resize(static_cast<std::size_t>(realization) + 1);
    return {p, &t[static_cast<std::size_t>(realization)]};
}

const State::Messages& State::message_of(int point, int realization) const {
    static const Messages none;
    const auto it = messages.find({point, realization});
    return it == messages.end() ? none : it->second;
}

StoreStatus State::status(const std::map<std::string, int>& counts) const {
    StoreStatus s;
    s.has_plan = !plan.points.empty();
    s.campaign_name = plan.name;
    s.physics_hash = s.has_plan ? plan.physics_hash() : 0;
    s.runs = runs;
    // The last run without an end record: what it runs now, or what ran when it was killed.
    if (!s.runs.empty() && !s.runs.back().end)
        s.runs.back().died_running = static_cast<int>(in_flight.size());
    for (std::size_t p = 0; p < plan.points.size(); ++p) {
        PointStatus ps;
        ps.label = plan.points[p].label;
        ps.planned = plan.points[p].realizations();
        ps.limit = plan.points[p].max_realizations();
        if (const auto cap = counts.find(ps.label);
            cap != counts.end() && cap->second < ps.planned) {
            ps.beyond_sweep = ps.planned - std::max(cap->second, 0);
            ps.planned = std::max(cap->second, 0);
            ps.limit = std::min(ps.limit, ps.planned);
        }
        const auto& t = tasks[p];
        for (std::size_t r = 0; r < t.size(); ++r) {
            const TaskEntry& e = t[r];
            if (static_cast<int>(r) >= ps.planned) {
                if (e.result) ++ps.extra;
                continue;
            }
            if (e.result) {
                ++ps.timed;
                ps.task_seconds += e.result->task_seconds;
            }
            switch (e.state) {
                case TaskState::done: {
                    ++ps.done;
                    const ResultSummary& rs = *e.result;
                    ps.jams += rs.n_jams;
                    ps.intervals += rs.n_intervals;
                    ps.uncensored += rs.n_uncensored;
                    ps.survival_sum += rs.survival_sum;
                    if (rs.empty_time) {
                        ++ps.emptied;
                        ps.empty_sum += *rs.empty_time;
                    }
                    break;
                }
                case TaskState::failed:
                    ++ps.failed;
                    s.failures.push_back(Failure{
                        ps.label, static_cast<int>(r),
                        seed_of(static_cast<int>(p), static_cast<int>(r)), e.result->rank, 0, false,
                        message_of(static_cast<int>(p), static_cast<int>(r)).result});
                    break;
                case TaskState::error:
                    ++ps.failed;
                    ++ps.errors;
                    if (e.deaths > 0) ++s.died;
                    s.failures.push_back(Failure{
                        ps.label, static_cast<int>(r),
                        seed_of(static_cast<int>(p), static_cast<int>(r)), 0, e.errors, true,
                        message_of(static_cast<int>(p), static_cast<int>(r)).last_error});
                    break;
                case TaskState::pending:
                    break;
            }
        }
        ps.pending = ps.planned - ps.done - ps.failed;
        s.total += ps.planned;
        s.done += ps.done;
        s.failed += ps.failed;
        s.errors += ps.errors;
        s.pending += ps.pending;
        s.points.push_back(ps);
    }
    return s;
}

void apply_record(State& state, RecordType type, std::uint64_t offset,
                  std::span<const std::uint8_t> payload, ReplaySink* sink) {
    switch (type) {
        case RecordType::run_start: {
            const bool changed = state.apply(decode_run_start(payload));
            if (sink) sink->run_start(state, changed);
            break;
        }
        case RecordType::result: {
            const ResultRecord r = decode_result_record(payload);
            const engine::RealizationResult res = decode_result(
                r.result, "result of '" + r.label + "' #" + std::to_string(r.realization));
            const std::int64_t row = state.apply(r, res);
            if (sink && row >= 0) sink->result(state, state.find_point(r.label), row, r, res);
            break;
        }
        case RecordType::error: {
            const ErrorRecord r = decode_error(payload);
            const int p = state.apply(r);
            if (sink) sink->error(state, p, r);
            break;
        }
        case RecordType::run_end: {
            const RunEndRecord r = decode_run_end(payload);
            state.apply(r);
            if (sink) sink->run_end(state, r);
            break;
        }
        case RecordType::sync:
            state.last_sync = decode_sync(payload);
            break;
        case RecordType::dispatch:
            state.apply(decode_dispatch(payload));
            break;
        case RecordType::allotment: {
            const AllotmentRecord r = decode_allotment(payload);
            const bool changed = state.apply(r);
            if (sink) sink->allotment(state, changed);
            break;
        }
    }
    state.last_type = type;
    state.last_offset = offset;
}

}  // namespace hopper::store
