#include "hopper/store/store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <fstream>
#include <random>
#include <system_error>

#include "h5.hpp"
#include "hopper/core/error.hpp"
#include "layout.hpp"
#include "state.hpp"

namespace hopper::store {

namespace fs = std::filesystem;

fs::path journal_path(const fs::path& store) {
    fs::path j = store;
    j += ".journal";
    return j;
}

namespace {

// Whether `p` exists; false only when it does not (or a directory on its way is missing). Any
// other failure to look (a symlink loop, no permission) is a StoreError naming the path, not a
// missing file.
bool exists_or_throw(const fs::path& p, const char* what) {
    std::error_code ec;
    const fs::file_status st = fs::status(p, ec);
    if (ec && ec != std::errc::no_such_file_or_directory && ec != std::errc::not_a_directory)
        throw core::StoreError(std::string("cannot access ") + what + " '" + p.string() +
                               "': " + ec.message());
    return fs::exists(st);
}

// A directory where a store file belongs is a mistake in the command line, not a damaged store.
void refuse_directory(const fs::path& p, const char* what) {
    std::error_code ec;
    if (fs::is_directory(p, ec))
        throw core::StoreError(std::string(what) + " '" + p.string() +
                               "' is a directory; a store is named by the path of its HDF5 file "
                               "(--store PATH), e.g. '" +
                               (p / "store.h5").string() + "'");
}

fs::path parent_or_dot(const fs::path& p) {
    return p.parent_path().empty() ? fs::path(".") : p.parent_path();
}

// Replays records into a state and an HDF5 writer (rebuild).
struct RebuildSink : ReplaySink {
    layout::Writer& w;
    std::int64_t since_flush = 0;
    explicit RebuildSink(layout::Writer& writer) : w(writer) {}
    void run_start(const State& s, bool changed) override { w.run_start(s, changed); }
    void result(const State& s, int point, std::int64_t row, const ResultRecord& rec,
                const engine::RealizationResult& r) override {
        w.result(s, point, row, rec, r);
        if (++since_flush >= 2000) {  // bounds the memory of buffered rows
            w.flush(s);
            since_flush = 0;
        }
    }
    void error(const State& s, int point, const ErrorRecord& rec) override {
        w.error(s, point, rec);
    }
    void run_end(const State& s, const RunEndRecord&) override { w.run_end(s); }
    void allotment(const State& s, bool changed) override { w.allotment(s, changed); }
};

}  // namespace

void write_from_journal(const fs::path& jpath, std::uint64_t limit, const fs::path& target,
                        const std::string& journal_name, std::uint64_t token,
                        std::uint64_t journal_bytes, const PointParameters& parameters,
                        State* into) {
    layout::Writer w = layout::Writer::create(target, journal_name, parameters);
    State own;
    State& fresh = into ? *into : own;
    RebuildSink sink(w);
    scan_journal(jpath, [&](RecordType t, std::uint64_t off, std::span<const std::uint8_t> p) {
        if (off < limit) apply_record(fresh, t, off, p, &sink);
    });
    w.flush(fresh);
    w.close(fresh, token, journal_bytes);
}

std::uint64_t random_token() {
    std::random_device rd;
    return (static_cast<std::uint64_t>(rd()) << 32) ^ rd() ^ 1u;
}

struct Store::Impl {
    // HDF5 prints no error stacks while a Store lives (its failures are exceptions); first, so
    // that it outlives every HDF5 handle below.
    h5::QuietErrors quiet;
    fs::path path;
    fs::path jpath;
    StoreOptions opt;
    std::optional<Journal> journal;
    State state;
    bool is_new = false;
    bool h5_in_step = false;
    std::vector<std::string> notes;
    std::optional<layout::Writer> writer;
    std::chrono::steady_clock::time_point last_flush{};
    bool run_open = false;
    int crash_passes = 0;
    int results_stored = 0;  // results of this process's runs made durable (the stop hook)
    // A batch (begin_batch .. commit): records written to the journal, not yet synced; their
    // HDF5 view updates wait for the sync.
    bool batch_open = false;
    bool unsynced = false;  // the journal holds records written in the batch
    struct Pending {
        int point = 0;
        std::int64_t row = -1;  // a result's row; -1: an error record
        ResultRecord result;    // its payload dropped (the view has the decoded result)
        engine::RealizationResult decoded;
        ErrorRecord error;
    };
    std::vector<Pending> pending;

    std::string where() const { return "store '" + path.string() + "'"; }

    // Test hook: SIGKILL the n-th time `point` is passed.
    void crash_point(const char* point) {
        if (opt.crash_point == point && ++crash_passes == opt.crash_after) ::raise(SIGKILL);
    }

    // Test hook: SIGSTOP once the stop_after_results-th result is durable (journal synced, view
    // updated), so that a test finds the run in a known state however loaded the machine is.
    void results_durable(int n) {
        const bool reached = opt.stop_after_results > 0 &&
                             results_stored < opt.stop_after_results &&
                             results_stored + n >= opt.stop_after_results;
        results_stored += n;
        if (reached) ::raise(SIGSTOP);
    }

    void rebuild() {
        fs::path tmp = path;
        tmp += ".rebuild";
        std::error_code ec;
        fs::remove(tmp, ec);
        // Consistent, but not a sync point (token 0). The replay builds the state again from
        // the journal, which holds everything the state does: it replaces the state instead of
        // being a second copy (the plan and tasks of 10^6 realizations twice was the master's
        // peak of memory: issue 44). A failure leaves it half built, and ends the run: the
        // store is then unusable until it is opened again (update_view's message says so).
        state = State{};
        write_from_journal(jpath, journal->size(), tmp, jpath.filename().string(), 0, 0,
                           opt.point_parameters, &state);
        fsync_path(tmp);
        crash_point("rebuild");
        fs::rename(tmp, path);
        fsync_path(parent_or_dot(path), true);
    }

    // Runs an update of the HDF5 view. Its failure (a full disk, a quota) is reported with what
    // it means: the journal already holds everything, the view is rebuilt by the next run.
    template <class F>
    void update_view(F&& update) {
        try {
            update();
        } catch (const core::StoreError& e) {
            throw core::StoreError(
                std::string(e.what()) + "\n  What this run finished is safe in the journal '" +
                jpath.string() +
                "'. Make room (or move the store with its journal) and run the "
                "same command again: it resumes, and rebuilds the HDF5 file from the journal");
        }
    }

    void maybe_flush() {
        const auto now = std::chrono::steady_clock::now();
        if (opt.flush_interval <= 0.0 ||
            std::chrono::duration<double>(now - last_flush).count() >= opt.flush_interval) {
            if (opt.crash_point == "hdf5" && ++crash_passes == opt.crash_after) {
                writer->flush(state, true);  // a partial update of the file, then die
                ::raise(SIGKILL);
            }
            writer->flush(state);
            last_flush = now;
        }
    }
};

Store::Store(const fs::path& path, StoreOptions options) : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.path = path;
    m.jpath = journal_path(path);
    m.opt = std::move(options);
    std::error_code ec;
    refuse_directory(path, "the store");
    refuse_directory(m.jpath, "the store's journal");
    const bool have_journal = exists_or_throw(m.jpath, "the store's journal");
    const bool have_h5 = exists_or_throw(path, "the store file");
    if (!have_journal && have_h5) {
        const layout::Inspection in = layout::inspect(path);
        if (in.readable)
            throw core::StoreError(
                m.where() + " has no journal '" + m.jpath.string() +
                "': the journal is the record of what finished and must stay beside the "
                "store; restore it, or use another --store path (the .h5 file alone can "
                "still be read for analysis)");
        throw core::StoreError(m.where() + " exists and is not a hopper store (" + in.problem +
                               "); use another --store path or move the file away");
    }
    if (!have_journal) fs::create_directories(parent_or_dot(path), ec);
    // Opens the journal, or creates it; a run that loses the race to create it opens the
    // winner's (and finds it locked).
    JournalScan scan;
    bool created = false;
    m.journal.emplace(Journal::open_or_create(
        m.jpath,
        [&](RecordType t, std::uint64_t off, std::span<const std::uint8_t> p) {
            apply_record(m.state, t, off, p, nullptr);
        },
        scan, created, JournalOptions{m.opt.require_lock, m.opt.before_journal_link}));
    if (scan.torn_bytes() > 0)
        m.notes.push_back("dropped an incomplete last journal record (" +
                          std::to_string(scan.torn_bytes()) +
                          " bytes, from an interrupted write); its realization runs again");
    if (m.state.duplicates > 0)
        m.notes.push_back("the journal holds " + std::to_string(m.state.duplicates) +
                          " duplicate results; the first of each is kept");
    m.is_new = m.state.runs.empty();
    const bool have_file = !created && exists_or_throw(path, "the store file");
    // A file closed in step whose checksum no longer matches was damaged afterwards: it is
    // rebuilt from the journal without being opened (damage can make HDF5 crash or loop).
    const FileCheck file_check =
        have_file ? check_closed_file(m.state, path) : FileCheck::unrecorded;
    if (file_check == FileCheck::changed) {
        m.notes.push_back(
            "the HDF5 file does not match the checksum recorded when it was closed "
            "(damaged since); rebuilding it from the journal without opening it");
    } else if (have_file) {
        const layout::Inspection in = layout::inspect(path);
        if (in.foreign)
            throw core::StoreError(m.where() + " is not a hopper store (" + in.problem +
                                   ") although its journal '" + m.jpath.string() +
                                   "' is; move the file away so that it can be rebuilt from "
                                   "the journal");
        // The HDF5 file is written after the journal, so it never holds more than the journal
        // knows -- unless the journal was replaced. Rebuilding would then destroy results.
        if (in.readable && in.rows > m.state.rows)
            throw core::StoreError(
                m.where() + " holds " + std::to_string(in.rows) +
                " realizations but its journal '" + m.jpath.string() + "' knows only " +
                std::to_string(m.state.rows) +
                ": the journal is not the one this file was written with (replaced or recreated?); "
                "nothing was changed. Restore the original journal, or move the .h5 file away to "
                "start from the journal");
        m.h5_in_step = in.readable && in.consistent && m.state.closed_in_step() &&
                       file_check != FileCheck::other && in.token == m.state.last_sync->token &&
                       in.journal_bytes == m.state.last_offset && in.rows == m.state.rows;
        if (!m.h5_in_step && !m.is_new)
            m.notes.push_back(in.readable
                                  ? "the HDF5 file is not in step with the journal (the last run "
                                    "did not close it); rebuilding it from the journal"
                                  : "the HDF5 file is damaged (" + in.problem +
                                        "); rebuilding it from the journal");
    } else if (!m.is_new) {
        m.notes.push_back("the HDF5 file is missing; rebuilding it from the journal");
    }
    if (m.opt.crash_point == "journal") m.journal->crash_after_appends(m.opt.crash_after - 1);
    if (!m.journal->locked())
        m.notes.push_back(
            "the file system does not support locks (--no-file-locking): nothing prevents two "
            "runs from writing this store at once");
}

Store::~Store() {
    // A run that did not end leaves the HDF5 file marked inconsistent; the next open rebuilds it.
    try {
        impl_->writer.reset();
    } catch (...) {
    }
}

const fs::path& Store::path() const {
    return impl_->path;
}
const CampaignPlan& Store::plan() const {
    return impl_->state.plan;
}
bool Store::is_new() const {
    return impl_->is_new;
}
const std::vector<std::string>& Store::notes() const {
    return impl_->notes;
}

const TaskEntry* Store::task(const std::string& label, int realization) const {
    const State& s = impl_->state;
    const int p = s.find_point(label);
    if (p < 0 || realization < 0) return nullptr;
    const auto& t = s.tasks[static_cast<std::size_t>(p)];
    return static_cast<std::size_t>(realization) < t.size()
               ? &t[static_cast<std::size_t>(realization)]
               : nullptr;
}

StoreStatus Store::status() const {
    StoreStatus s = impl_->state.status();
    s.store = impl_->path;
    s.writer_active = true;
    s.journal_bytes = impl_->journal->size();
    return s;
}

void Store::begin_run(RunStartRecord run) {
    Impl& m = *impl_;
    if (m.run_open) throw core::StoreError("internal: begin_run() twice");
    m.journal->append(RecordType::run_start, encode(run));
    const bool changed = m.state.apply(std::move(run));
    m.state.last_type = RecordType::run_start;
    if (m.h5_in_step) {
        try {
            m.writer.emplace(layout::Writer::open(m.path, m.opt.point_parameters));
        } catch (const core::StoreError& e) {
            m.notes.push_back(std::string("cannot open the HDF5 file for writing (") + e.what() +
                              "); rebuilding it");
            m.writer.reset();
        }
    }
    if (!m.writer) {
        // The run-start record is journaled: a failed rebuild (a full disk) loses nothing.
        m.update_view([&] {
            m.rebuild();
            m.writer.emplace(layout::Writer::open(m.path, m.opt.point_parameters));
        });
    } else {
        m.writer->run_start(m.state, changed);
    }
    m.h5_in_step = false;
    m.run_open = true;
    m.writer->flush(m.state);
    m.last_flush = std::chrono::steady_clock::now();
}

void Store::append(const ResultRecord& r) {
    Impl& m = *impl_;
    if (!m.run_open) throw core::StoreError("internal: append() outside a run");
    // Decode first: a record that cannot be read back never enters the journal.
    const engine::RealizationResult res =
        decode_result(r.result, "result of '" + r.label + "' #" + std::to_string(r.realization));
    if (m.state.find_point(r.label) < 0)
        throw core::StoreError("internal: result for unplanned point '" + r.label + "'");
    if (res.seed != r.seed)
        throw core::StoreError("internal: the result of '" + r.label + "' #" +
                               std::to_string(r.realization) + " has seed " +
                               std::to_string(res.seed) + ", its task " + std::to_string(r.seed));
    if (m.batch_open) {
        m.journal->append_unsynced(RecordType::result, encode(r));
        m.unsynced = true;
    } else
        m.journal->append(RecordType::result, encode(r));
    const std::int64_t row = m.state.apply(r, res);
    m.state.last_type = RecordType::result;
    if (m.batch_open) {
        if (row < 0) return;
        Impl::Pending p{m.state.find_point(r.label), row, r, res, {}};
        p.result.result.clear();
        m.pending.push_back(std::move(p));
        return;
    }
    m.update_view([&] {
        if (row >= 0) m.writer->result(m.state, m.state.find_point(r.label), row, r, res);
        m.maybe_flush();
    });
    m.results_durable(1);
}

void Store::begin_batch() {
    Impl& m = *impl_;
    if (!m.run_open) throw core::StoreError("internal: begin_batch() outside a run");
    m.batch_open = true;
}

void Store::commit() {
    Impl& m = *impl_;
    if (!m.batch_open) return;
    m.batch_open = false;
    std::vector<Impl::Pending> pending = std::move(m.pending);
    m.pending.clear();
    if (m.unsynced) m.journal->sync();
    m.unsynced = false;
    if (pending.empty()) return;
    m.update_view([&] {
        for (const Impl::Pending& p : pending) {
            if (p.row >= 0)
                m.writer->result(m.state, p.point, p.row, p.result, p.decoded);
            else
                m.writer->error(m.state, p.point, p.error);
        }
        m.maybe_flush();
    });
    m.results_durable(static_cast<int>(std::count_if(
        pending.begin(), pending.end(), [](const Impl::Pending& p) { return p.row >= 0; })));
}

void Store::allot(const AllotmentRecord& r) {
    Impl& m = *impl_;
    if (!m.run_open) throw core::StoreError("internal: allot() outside a run");
    commit();
    AllotmentRecord grow;
    for (const auto& p : r.points) {
        const int i = m.state.find_point(p.label);
        if (i < 0)
            throw core::StoreError("internal: allotment for unplanned point '" + p.label + "'");
        const int have = m.state.plan.points[static_cast<std::size_t>(i)].realizations();
        const int end = p.first + static_cast<int>(p.seeds.size());
        if (end <= have) continue;
        if (p.first > have)
            throw core::StoreError("internal: allotment of '" + p.label + "' from realization " +
                                   std::to_string(p.first) + " leaves a gap after " +
                                   std::to_string(have));
        // Only what is new: the record costs what the round adds.
        grow.points.push_back(PointAllotment{
            p.label, have,
            std::vector<std::uint64_t>(p.seeds.begin() + (have - p.first), p.seeds.end())});
    }
    if (grow.points.empty()) return;
    m.journal->append(RecordType::allotment, encode(grow));
    const bool changed = m.state.apply(grow);
    m.state.last_type = RecordType::allotment;
    m.update_view([&] {
        m.writer->allotment(m.state, changed);
        m.maybe_flush();
    });
}

void Store::append(const ErrorRecord& r) {
    Impl& m = *impl_;
    if (!m.run_open) throw core::StoreError("internal: append() outside a run");
    if (m.state.find_point(r.label) < 0)
        throw core::StoreError("internal: error for unplanned point '" + r.label + "'");
    if (m.batch_open) {
        m.journal->append_unsynced(RecordType::error, encode(r));
        m.unsynced = true;
    } else
        m.journal->append(RecordType::error, encode(r));
    const int p = m.state.apply(r);
    m.state.last_type = RecordType::error;
    if (m.batch_open) {
        m.pending.push_back(Impl::Pending{p, -1, {}, {}, r});
        return;
    }
    m.update_view([&] {
        m.writer->error(m.state, p, r);
        m.maybe_flush();
    });
}

void Store::dispatched(const DispatchRecord& r) {
    Impl& m = *impl_;
    if (!m.run_open) throw core::StoreError("internal: dispatched() outside a run");
    m.state.apply(r);  // first: an unplanned task is refused before it is journaled
    m.journal->append_unsynced(RecordType::dispatch, encode(r));
    m.state.last_type = RecordType::dispatch;
}

void Store::end_run(const RunEndRecord& r) {
    Impl& m = *impl_;
    if (!m.run_open) throw core::StoreError("internal: end_run() outside a run");
    commit();
    m.journal->append(RecordType::run_end, encode(r));
    m.state.apply(r);
    const std::uint64_t token = random_token();
    const std::uint64_t at = m.journal->size();
    m.update_view([&] {
        m.writer->run_end(m.state);
        m.writer->close(m.state, token, at);
    });
    m.writer.reset();
    fsync_path(m.path);
    m.crash_point("close");
    SyncRecord sync{token, at, static_cast<std::uint64_t>(m.state.rows), checksum_file(m.path)};
    m.journal->append(RecordType::sync, encode(sync));
    m.state.last_sync = sync;
    m.state.last_type = RecordType::sync;
    m.state.last_offset = at;
    m.run_open = false;
    m.h5_in_step = true;
}

StoreStatus read_status(const fs::path& store, const std::map<std::string, int>& counts) {
    const fs::path jpath = journal_path(store);
    std::error_code ec;
    refuse_directory(store, "the store");
    if (!exists_or_throw(jpath, "the store's journal")) {
        if (!exists_or_throw(store, "the store file"))
            throw core::StoreError("no store at '" + store.string() + "' (neither the file nor " +
                                   "its journal '" + jpath.string() + "' exists)");
        const layout::Inspection in = layout::inspect(store);
        throw core::StoreError(
            in.readable ? "store '" + store.string() + "' has no journal '" + jpath.string() +
                              "'; its progress is in the file's /tasks table (h5dump -g /tasks)"
                        : "'" + store.string() + "' is not a hopper store (" + in.problem + ")");
    }
    State state;
    const JournalScan scan =
        scan_journal(jpath, [&](RecordType t, std::uint64_t off, std::span<const std::uint8_t> p) {
            apply_record(state, t, off, p, nullptr);
        });
    StoreStatus s = state.status(counts);
    s.store = store;
    s.writer_active = journal_locked(jpath);
    s.hdf5_in_step = !s.writer_active && state.closed_in_step() && fs::exists(store, ec);
    // The journal says the file was closed in step; the file must still be the one closed (its
    // size and CRC-32C in the last sync record; read as plain bytes, without HDF5 and its file
    // lock, which a run starting meanwhile needs): a write of /analysis that failed on a full
    // disk leaves another file (issue 29, item 5). Stores synced before checksums: as recorded.
    if (s.hdf5_in_step) {
        const FileCheck check = check_closed_file(state, store);
        s.hdf5_in_step = check == FileCheck::intact || check == FileCheck::unrecorded;
    }
    s.journal_bytes = scan.valid_bytes;
    s.torn_bytes = scan.torn_bytes();
    s.plan = std::move(state.plan);
    return s;
}

std::vector<StoredRealization> read_realizations(const fs::path& store) {
    const h5::QuietErrors quiet;
    return layout::read_realizations(store);
}

void for_each_journal_realization(const fs::path& store,
                                  const std::function<void(StoredRealization&&)>& visit) {
    State state;
    struct Sink : ReplaySink {
        const std::function<void(StoredRealization&&)>& visit;
        explicit Sink(const std::function<void(StoredRealization&&)>& v) : visit(v) {}
        void result(const State&, int point, std::int64_t, const ResultRecord& rec,
                    const engine::RealizationResult& r) override {
            StoredRealization s;
            s.label = rec.label;
            s.point = point;
            s.record = rec;
            s.record.result.clear();
            s.result = r;
            visit(std::move(s));
        }
    } sink(visit);
    scan_journal(journal_path(store),
                 [&](RecordType t, std::uint64_t off, std::span<const std::uint8_t> p) {
                     apply_record(state, t, off, p, &sink);
                 });
}

std::vector<StoredRealization> read_journal_realizations(const fs::path& store) {
    std::vector<StoredRealization> out;
    for_each_journal_realization(store,
                                 [&](StoredRealization&& s) { out.push_back(std::move(s)); });
    return out;
}

Snapshot write_snapshot(const fs::path& store, const fs::path& out,
                        const PointParameters& point_parameters) {
    const h5::QuietErrors quiet;
    const fs::path src = journal_path(store);
    const fs::path dst = journal_path(out);
    refuse_directory(store, "the store");
    if (!exists_or_throw(src, "the store's journal"))
        throw core::StoreError("no journal '" + src.string() + "' beside '" + store.string() +
                               "': a snapshot is taken from the journal");
    for (const fs::path& p : {out, dst})
        if (exists_or_throw(p, "the snapshot"))
            throw core::StoreError("'" + p.string() +
                                   "' exists; a snapshot writes a new store (another path)");
    Snapshot snap;
    snap.writer_active = journal_locked(src);
    std::error_code ec;
    fs::create_directories(parent_or_dot(out), ec);
    // The journal is append-only: its bytes up to the moment of reading never change. A record
    // the writer is appending meanwhile is copied incomplete and dropped below as a torn tail.
    {
        std::ifstream in(src, std::ios::binary);
        std::ofstream copy(dst, std::ios::binary | std::ios::trunc);
        if (!in || !copy)
            throw core::StoreError("cannot copy the journal '" + src.string() + "' to '" +
                                   dst.string() + "'");
        copy << in.rdbuf();
        if (!copy.flush())
            throw core::StoreError("cannot write the snapshot's journal '" + dst.string() + "'");
    }
    State state;
    JournalScan scan;
    Journal journal = Journal::open(
        dst,
        [&](RecordType t, std::uint64_t off, std::span<const std::uint8_t> p) {
            apply_record(state, t, off, p, nullptr);
        },
        scan, JournalOptions{.require_lock = false, .before_link = {}});
    const std::uint64_t token = random_token();
    const std::uint64_t at = journal.size();
    write_from_journal(dst, at, out, dst.filename().string(), token, at, point_parameters);
    fsync_path(out);
    journal.append(
        RecordType::sync,
        encode(SyncRecord{token, at, static_cast<std::uint64_t>(state.rows), checksum_file(out)}));
    snap.realizations = state.rows;
    snap.journal_bytes = at;
    return snap;
}

}  // namespace hopper::store
