// `campaign merge`: stores of one campaign joined into a new store (docs/store.md, "Merging
// stores"). Works on the journals, the source of truth: the inputs' records are read without
// locks (as a snapshot reads them), checked against each other, and copied byte for byte into a
// new journal -- every run once, every realization once -- from which the HDF5 file is written
// with the code that rebuilds a store after a crash.

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <system_error>

#include "h5.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/journal.hpp"
#include "hopper/store/store.hpp"
#include "layout.hpp"
#include "state.hpp"

namespace hopper::store {

namespace fs = std::filesystem;

namespace {

// A record of an input's journal. A result's payload is read again when it is copied (a store
// with fields holds about 140 kB per realization: the inputs are not held in memory); the other
// records are small and kept.
struct Record {
    RecordType type = RecordType::result;
    Bytes payload;  // empty for a result
    // A result: where its payload is, its hash (checked when copied) and what is compared.
    std::uint64_t offset = 0, size = 0, hash = 0;
    std::string label;
    int realization = 0;
    std::uint64_t seed = 0, digest = 0;
    engine::Status status = engine::Status::failed;
};

std::uint64_t hash_of(std::span<const std::uint8_t> p) {
    return fnv1a64(std::string_view(reinterpret_cast<const char*>(p.data()), p.size()));
}

struct Input {
    fs::path path;
    std::vector<Record> records;  // every complete record but the sync records
    State state;
    std::uint64_t torn = 0;
};

[[noreturn]] void refuse(const std::string& why) {
    throw core::ConfigError("merge refused: " + why + "; nothing was written");
}

std::string q(const fs::path& p) {
    std::string s(1, '\'');
    s += p.native();
    s += '\'';
    return s;
}

// A record's bytes as a key (runs and records are identified by their bytes).
std::string key_of(const Bytes& b) {
    return std::string(reinterpret_cast<const char*>(b.data()), b.size());
}

bool present(const fs::path& p) {
    std::error_code ec;
    const bool e = fs::exists(p, ec);
    if (ec) refuse("cannot look at " + q(p) + " (" + ec.message() + ")");
    return e;
}

Input read_input(const fs::path& path) {
    Input in;
    in.path = path;
    const fs::path jpath = journal_path(path);
    std::error_code ec;
    if (fs::is_directory(path, ec)) refuse(q(path) + " is a directory, not a store");
    if (!present(jpath)) {
        if (!present(path))
            refuse("no store at " + q(path) + " (neither the file nor its journal " + q(jpath) +
                   " exists)");
        refuse(q(path) + " has no journal " + q(jpath) +
               ": a merge copies the journals, the record of what finished (keep each store's "
               "journal beside it)");
    }
    if (journal_locked(jpath))
        refuse(q(path) +
               " is being written by a `campaign run` (its journal is locked); merge "
               "it once that run has ended or been stopped");
    try {
        const JournalScan scan = scan_journal(
            jpath, [&](RecordType t, std::uint64_t off, std::span<const std::uint8_t> p) {
                apply_record(in.state, t, off, p, nullptr);
                if (t == RecordType::sync) return;
                Record rec;
                rec.type = t;
                if (t != RecordType::result) {
                    rec.payload.assign(p.begin(), p.end());
                } else {
                    const ResultRecord r = decode_result_record(p);
                    const engine::RealizationResult res = decode_result(r.result, "a result");
                    rec.offset = off + record_header_size;
                    rec.size = p.size();
                    rec.hash = hash_of(p);
                    rec.label = r.label;
                    rec.realization = r.realization;
                    rec.seed = r.seed;
                    rec.digest = physics_digest(res);
                    rec.status = res.status;
                }
                in.records.push_back(std::move(rec));
            });
        in.torn = scan.torn_bytes();
    } catch (const core::StoreError& e) {
        refuse("cannot read the journal of " + q(path) + ": " + e.what());
    }
    if (in.state.runs.empty()) refuse(q(path) + " holds no run (an empty journal)");
    // The HDF5 file is a view of the journal, which the merge reads. A view that lags behind (a
    // killed run) is fine; one that is not a store, or holds more than its journal knows, or was
    // closed in step with another journal, means the two files do not belong together.
    if (present(path)) {
        const layout::Inspection f = layout::inspect(path);
        if (f.foreign)
            refuse(q(path) + " is not a hopper store (" + f.problem + ") although its journal is");
        if (f.readable && f.rows > in.state.rows)
            refuse(q(path) + " holds " + std::to_string(f.rows) + " realizations but its journal " +
                   q(jpath) + " knows only " + std::to_string(in.state.rows) +
                   ": the journal and the HDF5 file disagree (the journal replaced?)");
        if (f.readable && f.consistent && f.token != 0 && in.state.closed_in_step() &&
            check_closed_file(in.state, path) != FileCheck::changed &&
            f.token != in.state.last_sync->token)
            refuse(q(path) + " was closed in step with another journal than " + q(jpath) +
                   " (its sync token differs): the journal and the HDF5 file disagree");
    }
    return in;
}

// "name=value" lines -> name -> value.
std::map<std::string, std::string> scene_lines(const std::string& scene) {
    std::map<std::string, std::string> out;
    std::istringstream is(scene);
    std::string line;
    while (std::getline(is, line)) {
        const auto eq = line.find('=');
        out[line.substr(0, eq)] = eq == std::string::npos ? "" : line.substr(eq + 1);
    }
    return out;
}

std::string scene_difference(const std::string& a, const std::string& b, const fs::path& pa,
                             const fs::path& pb) {
    const auto la = scene_lines(a), lb = scene_lines(b);
    std::set<std::string> names;
    for (const auto& [k, v] : la)
        names.insert(k);
    for (const auto& [k, v] : lb)
        names.insert(k);
    std::string out;
    int shown = 0;
    for (const auto& n : names) {
        const auto ia = la.find(n), ib = lb.find(n);
        const std::string va = ia == la.end() ? "(absent)" : ia->second;
        const std::string vb = ib == lb.end() ? "(absent)" : ib->second;
        if (va == vb) continue;
        if (shown++ < 4)
            out += (out.empty() ? "" : "; ") + n + " = " + va + " in " + q(pa) + ", " + vb +
                   " in " + q(pb);
    }
    if (shown > 4) out += "; and " + std::to_string(shown - 4) + " more";
    return out.empty() ? "the scene texts differ" : out;
}

void check_campaigns_agree(const std::vector<Input>& inputs) {
    const Input& first = inputs.front();
    struct Seen {
        const PointPlan* point;
        const fs::path* where;
    };
    std::map<std::string, Seen> points;
    for (const Input& in : inputs) {
        const CampaignPlan& plan = in.state.plan;
        if (plan.seed != first.state.plan.seed)
            refuse("the campaign seeds differ: " + q(first.path) + " has seed " +
                   std::to_string(first.state.plan.seed) + ", " + q(in.path) + " has seed " +
                   std::to_string(plan.seed) +
                   " (a merge joins stores of one campaign: the same [campaign] seed)");
        if (plan.name != first.state.plan.name)
            refuse("the campaign names differ: " + q(first.path) + " is '" + first.state.plan.name +
                   "', " + q(in.path) + " is '" + plan.name +
                   "' (a merge joins stores of one campaign: the same [campaign] name)");
        for (const PointPlan& p : plan.points) {
            const auto [it, added] = points.emplace(p.label, Seen{&p, &in.path});
            if (added) continue;
            const PointPlan& o = *it->second.point;
            if (o.scene != p.scene)
                refuse("point '" + p.label + "' has other physics in " + q(in.path) + " than in " +
                       q(*it->second.where) + " (" +
                       scene_difference(o.scene, p.scene, *it->second.where, in.path) + ")");
            const std::size_t n = std::min(o.seeds.size(), p.seeds.size());
            for (std::size_t r = 0; r < n; ++r)
                if (o.seeds[r] != p.seeds[r])
                    refuse("point '" + p.label + "' realization " + std::to_string(r) +
                           " has seed " + std::to_string(o.seeds[r]) + " in " +
                           q(*it->second.where) + " but " + std::to_string(p.seeds[r]) + " in " +
                           q(in.path));
        }
    }
}

// A result's payload read again from its input's journal, checked against the hash taken when
// it was scanned (the bytes of a journal before its end never change: it is append-only).
Bytes read_payload(const Input& in, const Record& rec) {
    std::ifstream f(journal_path(in.path), std::ios::binary);
    Bytes b(rec.size);
    if (!f.seekg(static_cast<std::streamoff>(rec.offset)) ||
        !f.read(reinterpret_cast<char*>(b.data()), static_cast<std::streamsize>(b.size())) ||
        hash_of(b) != rec.hash)
        throw core::StoreError("the journal of " + q(in.path) +
                               " changed while the merge read it (realization " +
                               std::to_string(rec.realization) + " of point '" + rec.label +
                               "'); nothing was written");
    return b;
}

struct Copy {
    std::size_t input;
    std::uint64_t digest;
    std::uint64_t seed;
    engine::Status status;
};

}  // namespace

MergeReport merge_stores(const std::vector<fs::path>& paths, const fs::path& out, RunInfo merge_run,
                         const PointParameters& point_parameters) {
    const h5::QuietErrors quiet;
    if (paths.empty()) refuse("no input stores (campaign merge A.h5 B.h5 ... --store C.h5)");
    const fs::path jout = journal_path(out);
    for (const fs::path& p : {out, jout})
        if (present(p))
            refuse(q(p) +
                   " exists; a merge writes a new store (choose another --store path, or move "
                   "the old store and its journal away)");
    std::vector<Input> inputs;
    for (const fs::path& p : paths)
        inputs.push_back(read_input(p));
    check_campaigns_agree(inputs);

    MergeReport report;
    // Every run once, in the order first seen (inputs in command-line order, each in journal
    // order); its records follow it. A run is its run-start record: a copy of a store resumed
    // elsewhere shares the runs before the copy, byte for byte.
    struct Run {
        const Bytes* start;
        std::vector<std::pair<std::size_t, const Record*>> records;  // (input, record)
        int inputs = 0;
    };
    std::vector<Run> runs;
    std::map<std::string, std::size_t> run_of;
    std::set<std::pair<RecordType, std::string>> copied;  // errors, allotments, run ends: once each
    std::map<std::pair<std::string, int>, Copy> results;
    for (std::size_t i = 0; i < inputs.size(); ++i) {
        Input& in = inputs[i];
        MergeInputSummary sum{in.path, in.state.rows, static_cast<int>(in.state.runs.size()),
                              in.torn};
        report.inputs.push_back(sum);
        std::optional<std::size_t> current;
        std::set<std::size_t> runs_here;
        for (const Record& rec : in.records) {
            if (rec.type == RecordType::run_start) {
                const auto [it, added] = run_of.emplace(key_of(rec.payload), runs.size());
                if (added) runs.push_back(Run{&rec.payload, {}, 0});
                current = it->second;
                if (runs_here.insert(*current).second) ++runs[*current].inputs;
                continue;
            }
            if (!current)  // the replay above refuses results before any run
                refuse("the journal of " + q(in.path) + " has records before its first run");
            if (rec.type == RecordType::result) {
                const std::string what = "realization " + std::to_string(rec.realization) +
                                         " of point '" + rec.label + "'";
                const Copy mine{i, rec.digest, rec.seed, rec.status};
                const auto [it, added] =
                    results.emplace(std::pair{rec.label, rec.realization}, mine);
                if (added) {
                    runs[*current].records.emplace_back(i, &rec);
                    continue;
                }
                const Copy& o = it->second;
                if (o.input == i) continue;  // a duplicate in one journal: its first is kept
                if (o.digest != mine.digest || o.seed != mine.seed || o.status != mine.status)
                    refuse(what + " differs between " + q(inputs[o.input].path) + " (seed " +
                           std::to_string(o.seed) + ", " + engine::to_string(o.status) +
                           ", physics digest " + hex64(o.digest) + ") and " + q(in.path) +
                           " (seed " + std::to_string(mine.seed) + ", " +
                           engine::to_string(mine.status) + ", physics digest " +
                           hex64(mine.digest) +
                           "): the same realization must give the same result (other code "
                           "versions or machines?)");
                ++report.identical_copies;
                continue;
            }
            if (copied.emplace(rec.type, key_of(rec.payload)).second)
                runs[*current].records.emplace_back(i, &rec);
        }
    }
    for (const Run& r : runs)
        if (r.inputs > 1) ++report.shared_runs;
    report.runs = static_cast<int>(runs.size());

    // The merge's own run: no points (the plan is the union of the runs above), the sweep of the
    // last run copied (what `campaign status` reads for a campaign with a target).
    RunStartRecord own;
    {
        const RunStartRecord last = decode_run_start(*runs.back().start);
        merge_run.sweep_path = last.run.sweep_path;
        merge_run.sweep_text = last.run.sweep_text;
        own.run = std::move(merge_run);
        own.plan.name = inputs.front().state.plan.name;
        own.plan.seed = inputs.front().state.plan.seed;
    }

    // Written under names private to this merge (a kill leaves only them behind, never a
    // store that looks complete), then put into place: the journal first (linked, so that a
    // journal that appeared meanwhile is never replaced), then the HDF5 file.
    const fs::path dir = out.parent_path().empty() ? fs::path(".") : out.parent_path();
    const std::string tag = ".merge-" + std::to_string(::getpid());
    fs::path jtmp = jout, htmp = out;
    jtmp += tag;
    htmp += tag;
    std::error_code ec;
    fs::create_directories(dir, ec);
    bool created = false, placed = false;
    try {
        Journal journal = Journal::create(jtmp);
        created = true;
        for (const Run& r : runs) {
            journal.append_unsynced(RecordType::run_start, *r.start);
            for (const auto& [i, rec] : r.records)
                journal.append_unsynced(rec->type, rec->type == RecordType::result
                                                       ? read_payload(inputs[i], *rec)
                                                       : rec->payload);
        }
        journal.append_unsynced(RecordType::run_start, encode(own));
        RunEndRecord end;
        end.end_time = utc_now();
        end.reason = "merged " + std::to_string(inputs.size()) + " stores";
        journal.append_unsynced(RecordType::run_end, encode(end));
        journal.sync();
        // The merged journal replayed: what the HDF5 file is written from, and the check that
        // nothing was lost or duplicated.
        State state;
        scan_journal(jtmp, [&](RecordType t, std::uint64_t off, std::span<const std::uint8_t> p) {
            apply_record(state, t, off, p, nullptr);
        });
        if (state.rows != static_cast<std::int64_t>(results.size()) || state.duplicates != 0)
            throw core::StoreError("internal: the merged journal holds " +
                                   std::to_string(state.rows) + " realizations, not " +
                                   std::to_string(results.size()));
        const std::uint64_t token = random_token();
        const std::uint64_t at = journal.size();
        write_from_journal(jtmp, at, htmp, jout.filename().string(), token, at, point_parameters);
        fsync_path(htmp);
        journal.append(RecordType::sync,
                       encode(SyncRecord{token, at, static_cast<std::uint64_t>(state.rows),
                                         checksum_file(htmp)}));
        if (::link(jtmp.c_str(), jout.c_str()) != 0) {
            const int err = errno;
            if (err == EEXIST) refuse(q(jout) + " appeared while the merge ran; it was left alone");
            throw core::StoreError("cannot put the merged journal into place as " + q(jout) + " (" +
                                   std::strerror(err) + ")");
        }
        placed = true;
        fs::remove(jtmp);
        if (present(out)) refuse(q(out) + " appeared while the merge ran; it was left alone");
        fs::rename(htmp, out);
        fsync_path(dir, true);
        report.realizations = state.rows;
        report.points = static_cast<int>(state.plan.points.size());
    } catch (...) {
        if (created) {
            fs::remove(htmp, ec);
            fs::remove(jtmp, ec);
            if (placed) fs::remove(jout, ec);
        }
        throw;
    }
    return report;
}

}  // namespace hopper::store
