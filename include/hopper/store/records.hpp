#pragma once
// What the store records: the campaign plan (points, their physics and seeds), one entry per run
// (provenance), each finished realization, each failed attempt, the end of a run, and the marker
// that the HDF5 file was closed in step with the journal. Each is one journal record
// (journal.hpp); the HDF5 file (store.hpp) is built from them.

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "hopper/core/setting.hpp"
#include "hopper/store/codec.hpp"

namespace hopper::store {

// One point of a campaign as the store knows it. Identity is the label (its settings); the
// physics is the canonical text of every scene parameter, so a changed base section is caught
// even when the label is the same.
struct PointPlan {
    std::string label;  // "D_cm=2.7 theta_deg=45 material.mu=0.5"
    // Canonical "name=value" lines of every scene parameter (SI units): a physics fingerprint,
    // hashed and compared, never parsed back into values (`parameters` are for that).
    std::string scene;
    // The /points columns D_cm, theta_deg, particles (D and theta through SI and back: 60 may
    // read 59.99999999999999; the typed settings keep the values as written).
    double D_cm = 0.0;
    double theta_deg = 0.0;
    int particles = 0;
    // Realization r -> its seed, for the realizations allotted so far: all of them in a campaign
    // without a target; with one, those of the rounds decided so far (AllotmentRecord extends
    // the list round by round), so that the plan costs what is planned, not max_realizations.
    std::vector<std::uint64_t> seeds;
    // The most realizations the point may have: max_realizations with a target, else its
    // realizations. Read as seeds.size() from plans recorded before it (issue 29).
    int limit = 0;
    // Typed settings (core/setting.hpp). `settings`: what the label shows (the point's varied
    // settings, canonical order); `parameters`: every scene parameter under its sweep-file name
    // and unit. Empty when read from a journal written before they were recorded (the campaign
    // layer recovers them from the run's recorded sweep text).
    std::vector<core::Setting> settings;
    std::vector<core::Setting> parameters;
    std::uint64_t physics_hash() const { return fnv1a64(scene); }
    // Realizations allotted so far (the current round's end with a target).
    int realizations() const { return static_cast<int>(seeds.size()); }
    int max_realizations() const { return std::max(limit, realizations()); }
};

struct CampaignPlan {
    std::string name;
    std::uint64_t seed = 0;  // the campaign seed
    std::vector<PointPlan> points;
    // Hash of the campaign seed and every point's (label, physics), independent of point order.
    std::uint64_t physics_hash() const;
    const PointPlan* find(const std::string& label) const;
};

// A campaign with a target extends its points' allotments round by round (campaign/adaptive.hpp):
// the master records each extension before it hands out the round's realizations. For each point
// whose allotment grows: the seeds of realizations [first, first + seeds.size()). Replaying the
// rounds from the stored results gives the same allotments, so the record is bookkeeping for
// readers (status, the /tasks table), never a decision.
struct PointAllotment {
    std::string label;
    int first = 0;
    std::vector<std::uint64_t> seeds;
};
struct AllotmentRecord {
    std::vector<PointAllotment> points;
};

// Provenance of one `campaign run` (one allocation, one resume).
struct RunInfo {
    std::string start_time;  // ISO 8601 UTC
    std::string code_version;
    std::string compiler;
    std::string command;  // the command line
    std::string sweep_path;
    std::string sweep_text;
    int mpi_size = 1;  // processes (1 without mpirun)
    int workers = 1;
    std::vector<std::string> hosts;  // one per process, rank order
    std::int64_t pid = 0;            // of the master
};

struct RunStartRecord {
    RunInfo run;
    CampaignPlan plan;  // the plan of this run's sweep file
};

// One finished realization (any status, failed included).
struct ResultRecord {
    std::string label;
    int realization = 0;
    std::uint64_t seed = 0;
    int rank = 0;                // the worker: its MPI rank, or its thread number (1..) without MPI
    int attempt = 1;             // 1 for the first try
    double task_seconds = 0.0;   // wall-clock time on the worker, scene building included
    double finished_unix = 0.0;  // when the master stored it, s since 1970 UTC
    Bytes result;                // encode_result(RealizationResult)
};

// One attempt that ended in an exception (no result). The task stays pending.
struct ErrorRecord {
    std::string label;
    int realization = 0;
    std::uint64_t seed = 0;
    int rank = 0;
    int attempt = 1;
    double time_unix = 0.0;
    std::string reason;
};

// A realization handed to a worker (issue 44): written (not synced) as the master hands it out,
// so that a run that dies without its run-end record (its processes killed: the kernel's OOM
// killer, a crash, a lost node) tells which realizations were running when it died. Replay
// counts, per task, the runs that died while it ran (TaskEntry::deaths).
struct DispatchRecord {
    std::string label;
    int realization = 0;
    std::uint64_t seed = 0;
    int rank = 0;
    int attempt = 1;
    double time_unix = 0.0;
};

struct RunEndRecord {
    std::string end_time;  // ISO 8601 UTC
    std::string reason;    // "complete", "interrupted by SIGTERM", ...
    int stored = 0;        // realizations stored by this run
    double wall_seconds = 0.0;
    double master_cpu_seconds = 0.0;
    // Worker seconds of realizations interrupted in this run that no checkpoint keeps (computed
    // again later: thrown away), and those kept in checkpoint files (continued later). Records
    // written before these existed read as 0.
    double lost_worker_seconds = 0.0;
    double saved_worker_seconds = 0.0;
};

// The size and CRC-32C of a closed HDF5 file: damage after the close (a disk error flipping
// bytes) shows as a mismatch, found without opening the file with HDF5.
struct FileChecksum {
    std::uint64_t bytes = 0;
    std::uint32_t crc32c = 0;
    bool operator==(const FileChecksum&) const = default;
};
// Reads the whole file (core::StoreError when it cannot).
FileChecksum checksum_file(const std::filesystem::path& path);

// Written after the HDF5 file was closed and synced: the file then holds exactly the journal's
// first `journal_bytes` bytes, and carries `token` as an attribute. `campaign analyze` writes
// another one after replacing /analysis (same token, the new length and checksum).
struct SyncRecord {
    std::uint64_t token = 0;
    std::uint64_t journal_bytes = 0;
    std::uint64_t rows = 0;            // rows in /realizations
    std::optional<FileChecksum> file;  // absent in sync records written before checksums
};

Bytes encode(const RunStartRecord& r);
Bytes encode(const ResultRecord& r);
Bytes encode(const ErrorRecord& r);
Bytes encode(const RunEndRecord& r);
Bytes encode(const SyncRecord& r);
Bytes encode(const AllotmentRecord& r);
Bytes encode(const DispatchRecord& r);
RunStartRecord decode_run_start(std::span<const std::uint8_t> b);
ResultRecord decode_result_record(std::span<const std::uint8_t> b);
ErrorRecord decode_error(std::span<const std::uint8_t> b);
RunEndRecord decode_run_end(std::span<const std::uint8_t> b);
SyncRecord decode_sync(std::span<const std::uint8_t> b);
AllotmentRecord decode_allotment(std::span<const std::uint8_t> b);
DispatchRecord decode_dispatch(std::span<const std::uint8_t> b);

// The current time as ISO 8601 UTC ("2024-05-01T12:00:00Z") and as seconds since 1970.
std::string utc_now();
double unix_now();

}  // namespace hopper::store
