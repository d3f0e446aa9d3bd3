#pragma once
// The store's journal: an append-only file of length-prefixed, checksummed records beside the
// HDF5 file (STORE.h5.journal). It is the source of truth for what has finished: a realization
// counts as done once its record is written and fdatasync'd. A kill at any moment can leave at
// most the last record incomplete; its checksum exposes it and the next writer drops it (that
// realization simply runs again).
//
// File layout: 16-byte header "HOPPER-JOURNAL" + u16 version (1), then records:
//   u32 magic "HJRC" | u8 type | 3 zero bytes | u32 payload length | u32 CRC-32C | payload
// The CRC covers the type, the length and the payload. All integers little-endian.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>

#include "hopper/store/codec.hpp"

namespace hopper::store {

enum class RecordType : std::uint8_t {
    run_start = 1,  // RunStartRecord
    result = 2,     // ResultRecord
    error = 3,      // ErrorRecord
    run_end = 4,    // RunEndRecord
    sync = 5,       // SyncRecord
    allotment = 6,  // AllotmentRecord (issue 29: a target campaign's plan grows by rounds)
    dispatch = 7,   // DispatchRecord (issue 44: what ran when a run died)
};

inline constexpr std::size_t journal_header_size = 16;
inline constexpr std::size_t record_header_size = 16;

// What a scan found.
struct JournalScan {
    std::uint64_t valid_bytes = 0;  // header + every complete record
    std::uint64_t file_bytes = 0;
    std::uint64_t records = 0;
    std::uint64_t torn_bytes() const { return file_bytes - valid_bytes; }
};

// Calls `visit(type, offset, payload)` for every complete record in order. An incomplete or
// corrupt tail (nothing valid after it) ends the scan and is reported as torn bytes; a bad
// record followed by valid ones means the file was damaged (not by a crash): core::StoreError.
// A missing or foreign file header is a StoreError too. Reads without locking, so it works
// while a writer appends (its record in progress counts as the torn tail).
using RecordVisitor =
    std::function<void(RecordType, std::uint64_t offset, std::span<const std::uint8_t>)>;
JournalScan scan_journal(const std::filesystem::path& path, const RecordVisitor& visit);

// Test hook of Journal::create: called once the new journal is complete and locked under its
// private temporary name, before it is linked into place (tests pause there to make two
// creators race deterministically).
using BeforeLinkHook = std::function<void()>;

struct JournalOptions {
    // A file system without locks (NFS without a lock daemon, Lustre without flock): true
    // refuses to write (StoreError naming the switch), false goes on unprotected (locked() is
    // then false). A lock held by another process is refused either way.
    bool require_lock = true;
    BeforeLinkHook before_link;  // test hook of create(), see above
};

// The writer's handle: holds an exclusive lock (fcntl) on the journal while open.
class Journal {
  public:
    // Creates the file: written and locked under a name private to this call, then linked into
    // place (exclusive: never replaces a journal), fsync of file and directory. Throws if a
    // journal exists at `path`.
    static Journal create(const std::filesystem::path& path, const JournalOptions& options = {});
    // Opens for appending: takes the lock, scans (calling `visit` per record, as scan_journal)
    // and drops a torn tail (truncates to scan.valid_bytes, fsync'd).
    static Journal open(const std::filesystem::path& path, const RecordVisitor& visit,
                        JournalScan& scan, const JournalOptions& options = {});
    // Opens the journal at `path`, or creates it when there is none. Two processes calling this
    // at once end with one journal: the loser of the creation opens the winner's, which is
    // locked ("in use by another `campaign run`") or, once the winner is done, resumed.
    // `created` tells which happened.
    static Journal open_or_create(const std::filesystem::path& path, const RecordVisitor& visit,
                                  JournalScan& scan, bool& created,
                                  const JournalOptions& options = {});

    Journal(Journal&& o) noexcept;
    Journal& operator=(Journal&& o) noexcept;
    Journal(const Journal&) = delete;
    Journal& operator=(const Journal&) = delete;
    ~Journal();

    // Writes one record and fdatasync's it. Returns the record's offset. Throws when the file
    // at path() is no longer the one this handle writes (the journal was deleted or replaced
    // while the run wrote it): the record would be lost with the orphaned file.
    std::uint64_t append(RecordType type, std::span<const std::uint8_t> payload);
    // The same without the fdatasync, for a journal written whole under a private name before it
    // is put into place (campaign merge); sync() then makes it durable at once.
    std::uint64_t append_unsynced(RecordType type, std::span<const std::uint8_t> payload);
    void sync();
    std::uint64_t size() const { return size_; }
    const std::filesystem::path& path() const { return path_; }
    // False when the file system does not support locks and the options allowed that (then two
    // runs are not prevented).
    bool locked() const { return locked_; }

    // Test hook: after this many more append() calls, the next one writes only half its record
    // and raises SIGKILL (a crash in the middle of a write). Negative = off.
    void crash_after_appends(int n) { crash_countdown_ = n; }

  private:
    Journal(std::filesystem::path path, int fd, std::uint64_t size, bool locked);
    void lock_or_throw(bool require_lock);
    std::uint64_t append_record(RecordType type, std::span<const std::uint8_t> payload, bool sync);
    // Throws unless the file at path_ is the one fd_ refers to.
    void check_still_in_place() const;

    std::filesystem::path path_;
    int fd_ = -1;
    std::uint64_t size_ = 0;
    bool locked_ = false;
    int crash_countdown_ = -1;
};

// Whether some process holds the journal's write lock (a `campaign run` is writing).
bool journal_locked(const std::filesystem::path& path);

}  // namespace hopper::store
