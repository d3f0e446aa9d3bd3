#include "hopper/store/journal.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

#include "hopper/core/error.hpp"

namespace hopper::store {

namespace fs = std::filesystem;

namespace {

constexpr char header_magic[14] = {'H', 'O', 'P', 'P', 'E', 'R', '-',
                                   'J', 'O', 'U', 'R', 'N', 'A', 'L'};
constexpr std::uint16_t journal_version = 1;
constexpr std::uint32_t record_magic = 0x43524A48;  // "HJRC" little-endian
// A single record larger than this is not something we write: treat it as damage.
constexpr std::uint32_t max_payload = 1u << 30;

[[noreturn]] void fail_errno(const std::string& what, const fs::path& path) {
    throw core::StoreError(what + " '" + path.string() + "': " + std::strerror(errno));
}

std::uint32_t get_u32(const std::uint8_t* p) {
    return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
           static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

void put_u32(std::uint8_t* p, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

void read_exact(int fd, std::uint8_t* buf, std::size_t n, std::uint64_t offset,
                const fs::path& path) {
    std::size_t done = 0;
    while (done < n) {
        const ssize_t r = ::pread(fd, buf + done, n - done, static_cast<off_t>(offset + done));
        if (r < 0) {
            if (errno == EINTR) continue;
            fail_errno("cannot read the journal", path);
        }
        if (r == 0) throw core::StoreError("journal '" + path.string() + "' shrank while read");
        done += static_cast<std::size_t>(r);
    }
}

void write_all(int fd, const std::uint8_t* buf, std::size_t n, std::uint64_t offset,
               const fs::path& path) {
    std::size_t done = 0;
    while (done < n) {
        const ssize_t w = ::pwrite(fd, buf + done, n - done, static_cast<off_t>(offset + done));
        if (w < 0) {
            if (errno == EINTR) continue;
            fail_errno("cannot write the journal", path);
        }
        done += static_cast<std::size_t>(w);
    }
}

// The record header's checksum: type, length and payload.
std::uint32_t record_crc(std::uint8_t type, std::uint32_t length,
                         std::span<const std::uint8_t> payload) {
    std::uint8_t head[8] = {type, 0, 0, 0};
    put_u32(head + 4, length);
    return crc32c(payload, crc32c(std::span<const std::uint8_t>(head, 8)));
}

// Whether a complete, valid record starts at `at` in `data`.
bool valid_record_at(std::span<const std::uint8_t> data, std::size_t at) {
    if (at + record_header_size > data.size()) return false;
    const std::uint8_t* h = data.data() + at;
    if (get_u32(h) != record_magic) return false;
    const std::uint32_t len = get_u32(h + 8);
    if (len > max_payload || at + record_header_size + len > data.size()) return false;
    return get_u32(h + 12) == record_crc(h[4], len, data.subspan(at + record_header_size, len));
}

void sync_directory(const fs::path& file) {
    const fs::path dir = file.parent_path().empty() ? fs::path(".") : file.parent_path();
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
    if (fd < 0) return;  // best effort: some file systems do not allow it
    ::fsync(fd);
    ::close(fd);
}

JournalScan scan_fd(int fd, const fs::path& path, const RecordVisitor& visit) {
    struct stat st {};
    if (::fstat(fd, &st) != 0) fail_errno("cannot stat the journal", path);
    JournalScan scan;
    scan.file_bytes = static_cast<std::uint64_t>(st.st_size);
    const std::string where = "journal '" + path.string() + "'";
    if (scan.file_bytes < journal_header_size)
        throw core::StoreError(where + " is too short to be a hopper journal (" +
                               std::to_string(scan.file_bytes) + " bytes)");
    std::uint8_t header[journal_header_size];
    read_exact(fd, header, journal_header_size, 0, path);
    if (std::memcmp(header, header_magic, sizeof header_magic) != 0)
        throw core::StoreError(where + " is not a hopper journal (bad header)");
    const std::uint16_t version = static_cast<std::uint16_t>(header[14] | header[15] << 8);
    if (version != journal_version)
        throw core::StoreError(where + " has format version " + std::to_string(version) +
                               "; this build reads version " + std::to_string(journal_version));

    std::uint64_t pos = journal_header_size;
    std::vector<std::uint8_t> payload;
    while (pos < scan.file_bytes) {
        bool ok = false;
        std::uint8_t h[record_header_size];
        std::uint32_t len = 0;
        if (pos + record_header_size <= scan.file_bytes) {
            read_exact(fd, h, record_header_size, pos, path);
            len = get_u32(h + 8);
            if (get_u32(h) == record_magic && len <= max_payload &&
                pos + record_header_size + len <= scan.file_bytes) {
                payload.resize(len);
                read_exact(fd, payload.data(), len, pos + record_header_size, path);
                ok = get_u32(h + 12) == record_crc(h[4], len, payload);
            }
        }
        if (!ok) {
            // A crash tears only the last record. Anything valid after this point means damage.
            std::vector<std::uint8_t> rest(scan.file_bytes - pos);
            read_exact(fd, rest.data(), rest.size(), pos, path);
            for (std::size_t at = 1; at + record_header_size <= rest.size(); ++at)
                if (valid_record_at(rest, at))
                    throw core::StoreError(
                        where + " is damaged: an invalid record at byte " + std::to_string(pos) +
                        " is followed by valid ones (a crash cannot do that; restore the store "
                        "from a backup, or move the journal away to start a new store)");
            break;
        }
        const std::uint8_t type = h[4];
        if (type < 1 || type > 7)
            throw core::StoreError(where + ": unknown record type " + std::to_string(type) +
                                   " at byte " + std::to_string(pos) +
                                   " (written by a newer version?)");
        try {
            visit(static_cast<RecordType>(type), pos, payload);
        } catch (const core::StoreError& e) {
            // Name the file and the record: the decoders only know what they were reading.
            static const char* const names[] = {"",        "run start", "result",   "error",
                                                "run end", "sync",      "allotment"};
            throw core::StoreError(where + " is damaged: its " + names[type] + " record at byte " +
                                   std::to_string(pos) + " has a valid checksum but cannot be " +
                                   "used: " + e.what());
        }
        pos += record_header_size + len;
        scan.valid_bytes = pos;
        ++scan.records;
    }
    if (scan.valid_bytes == 0) scan.valid_bytes = journal_header_size;
    return scan;
}

struct flock whole_file_lock(short type) {
    struct flock fl {};
    fl.l_type = type;
    fl.l_whence = SEEK_SET;
    fl.l_start = 0;
    fl.l_len = 0;
    return fl;
}

}  // namespace

JournalScan scan_journal(const fs::path& path, const RecordVisitor& visit) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) fail_errno("cannot open the journal", path);
    try {
        JournalScan s = scan_fd(fd, path, visit);
        ::close(fd);
        return s;
    } catch (...) {
        ::close(fd);
        throw;
    }
}

bool journal_locked(const fs::path& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return false;
    struct flock fl = whole_file_lock(F_WRLCK);
    const bool locked = ::fcntl(fd, F_OFD_GETLK, &fl) == 0 && fl.l_type != F_UNLCK;
    ::close(fd);
    return locked;
}

Journal::Journal(fs::path path, int fd, std::uint64_t size, bool locked)
    : path_(std::move(path)), fd_(fd), size_(size), locked_(locked) {}

Journal::Journal(Journal&& o) noexcept
    : path_(std::move(o.path_)),
      fd_(std::exchange(o.fd_, -1)),
      size_(o.size_),
      locked_(o.locked_),
      crash_countdown_(o.crash_countdown_) {}

Journal& Journal::operator=(Journal&& o) noexcept {
    if (this != &o) {
        if (fd_ >= 0) ::close(fd_);
        path_ = std::move(o.path_);
        fd_ = std::exchange(o.fd_, -1);
        size_ = o.size_;
        locked_ = o.locked_;
        crash_countdown_ = o.crash_countdown_;
    }
    return *this;
}

Journal::~Journal() {
    if (fd_ >= 0) ::close(fd_);  // releases the lock
}

void Journal::lock_or_throw(bool require_lock) {
    // An open-file-description lock (Linux): it conflicts within one process too, and closing
    // another descriptor of the file does not release it.
    struct flock fl = whole_file_lock(F_WRLCK);
    if (::fcntl(fd_, F_OFD_SETLK, &fl) == 0) {
        locked_ = true;
        return;
    }
    const int err = errno;
    if (err == EACCES || err == EAGAIN) {
        ::close(fd_);
        fd_ = -1;
        throw core::StoreError("the store's journal '" + path_.string() +
                               "' is in use by another `campaign run`; wait for it to finish "
                               "or stop it first");
    }
    locked_ = false;
    if (!require_lock) return;  // the caller accepted a file system without locks
    ::close(fd_);
    fd_ = -1;
    throw core::StoreError(
        "cannot lock the store's journal '" + path_.string() + "': " + std::strerror(err) +
        ". The file system does not support locks (NFS without a lock daemon, Lustre mounted "
        "without flock); they are what keeps two `campaign run` from writing one store. Use a "
        "file system with locks for the store, or make sure only one run uses it at a time and "
        "run with --no-file-locking (which also turns HDF5's file locking off)");
}

Journal Journal::create(const fs::path& path, const JournalOptions& options) {
    // Written under a name private to this call and linked into place complete, so that a
    // reader never sees a journal without its header and two runs cannot both create it. The
    // private name matters: a shared one ("<journal>.new") let one run unlink the other's file
    // before it was linked, leaving the other writing every record to a deleted file.
    std::random_device rd;
    char suffix[48];
    std::snprintf(suffix, sizeof suffix, ".new.%ld.%08x", static_cast<long>(::getpid()), rd());
    fs::path tmp = path;
    tmp += suffix;
    const int fd = ::open(tmp.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) fail_errno("cannot create the journal", tmp);
    struct Unlink {  // the private name goes whatever happens
        const fs::path& p;
        ~Unlink() { ::unlink(p.c_str()); }
    } unlink_tmp{tmp};
    Journal j(path, fd, 0, false);
    j.lock_or_throw(options.require_lock);
    std::uint8_t header[journal_header_size] = {};
    std::memcpy(header, header_magic, sizeof header_magic);
    header[14] = static_cast<std::uint8_t>(journal_version & 0xff);
    header[15] = static_cast<std::uint8_t>(journal_version >> 8);
    write_all(fd, header, sizeof header, 0, tmp);
    if (::fsync(fd) != 0) fail_errno("cannot sync the journal", tmp);
    if (options.before_link) options.before_link();
    if (::link(tmp.c_str(), path.c_str()) != 0) {
        if (errno == EEXIST) fail_errno("cannot create the journal", path);
        if (errno != EPERM && errno != ENOTSUP && errno != EOPNOTSUPP && errno != ENOSYS)
            fail_errno("cannot link the new journal into place as", path);
        // A file system without hard links: a rename that refuses to replace; where even that
        // is missing, the final name created exclusively (a reader may then briefly see a
        // journal shorter than its header).
        if (::renameat2(AT_FDCWD, tmp.c_str(), AT_FDCWD, path.c_str(), RENAME_NOREPLACE) != 0) {
            if (errno == EEXIST) fail_errno("cannot create the journal", path);
            const int direct = ::open(path.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
            if (direct < 0) fail_errno("cannot create the journal", path);
            Journal d(path, direct, 0, false);
            d.lock_or_throw(options.require_lock);
            write_all(direct, header, sizeof header, 0, path);
            if (::fsync(direct) != 0) fail_errno("cannot sync the journal", path);
            j = std::move(d);
        }
    }
    sync_directory(path);
    j.size_ = journal_header_size;
    j.check_still_in_place();
    return j;
}

Journal Journal::open_or_create(const fs::path& path, const RecordVisitor& visit, JournalScan& scan,
                                bool& created, const JournalOptions& options) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0 && errno == ENOENT) {
        try {
            Journal j = create(path, options);
            created = true;
            scan = JournalScan{journal_header_size, journal_header_size, 0};
            return j;
        } catch (const core::StoreError&) {
            // Another run created it between our look and our link: use theirs.
            if (::stat(path.c_str(), &st) != 0) throw;
        }
    }
    created = false;
    return open(path, visit, scan, options);
}

void Journal::check_still_in_place() const {
    struct stat mine {
    }, there{};
    if (::fstat(fd_, &mine) != 0) fail_errno("cannot stat the journal", path_);
    const bool same = ::stat(path_.c_str(), &there) == 0 && there.st_dev == mine.st_dev &&
                      there.st_ino == mine.st_ino;
    if (!same)
        throw core::StoreError(
            "the store's journal '" + path_.string() +
            "' was deleted or replaced while this `campaign run` was writing it; what this run "
            "recorded since is not in the journal at that path. Stop every other program using "
            "the store, then run the same command again: it resumes from what the journal holds");
}

Journal Journal::open(const fs::path& path, const RecordVisitor& visit, JournalScan& scan,
                      const JournalOptions& options) {
    const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) fail_errno("cannot open the journal", path);
    Journal j(path, fd, 0, false);
    j.lock_or_throw(options.require_lock);
    scan = scan_fd(fd, path, visit);
    if (scan.valid_bytes < scan.file_bytes) {
        if (::ftruncate(fd, static_cast<off_t>(scan.valid_bytes)) != 0)
            fail_errno("cannot drop the torn last record of the journal", path);
        if (::fsync(fd) != 0) fail_errno("cannot sync the journal", path);
    }
    j.size_ = scan.valid_bytes;
    return j;
}

std::uint64_t Journal::append(RecordType type, std::span<const std::uint8_t> payload) {
    return append_record(type, payload, true);
}

std::uint64_t Journal::append_unsynced(RecordType type, std::span<const std::uint8_t> payload) {
    return append_record(type, payload, false);
}

void Journal::sync() {
    if (::fdatasync(fd_) != 0) fail_errno("cannot sync the journal", path_);
}

std::uint64_t Journal::append_record(RecordType type, std::span<const std::uint8_t> payload,
                                     bool sync) {
    if (payload.size() > max_payload)
        throw core::StoreError("a journal record of " + std::to_string(payload.size()) +
                               " bytes is too large");
    std::vector<std::uint8_t> rec(record_header_size + payload.size());
    put_u32(rec.data(), record_magic);
    rec[4] = static_cast<std::uint8_t>(type);
    const auto len = static_cast<std::uint32_t>(payload.size());
    put_u32(rec.data() + 8, len);
    put_u32(rec.data() + 12, record_crc(rec[4], len, payload));
    std::memcpy(rec.data() + record_header_size, payload.data(), payload.size());
    if (crash_countdown_ == 0) {
        write_all(fd_, rec.data(), rec.size() / 2, size_, path_);
        ::fdatasync(fd_);
        ::raise(SIGKILL);
    }
    if (crash_countdown_ > 0) --crash_countdown_;
    const std::uint64_t at = size_;
    try {
        write_all(fd_, rec.data(), rec.size(), at, path_);
        if (sync && ::fdatasync(fd_) != 0) fail_errno("cannot sync the journal", path_);
    } catch (const core::StoreError& e) {
        // A full disk or a quota: take the partial record back (best effort; a torn tail is
        // dropped by the next run anyway) and say what it means.
        if (::ftruncate(fd_, static_cast<off_t>(at)) == 0) ::fdatasync(fd_);
        throw core::StoreError(std::string(e.what()) +
                               "; this record was not written, and what finished before it is safe "
                               "in the journal: make room and run the same command again to "
                               "resume");
    }
    size_ += rec.size();
    check_still_in_place();
    return at;
}

}  // namespace hopper::store
