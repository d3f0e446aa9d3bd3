// The journal: records come back in order; a torn last record (a kill in the middle of a write,
// at any byte) is dropped; damage elsewhere, foreign files and a second writer are refused.

#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <condition_variable>
#include <csignal>
#include <fstream>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "fixtures.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/journal.hpp"

namespace hopper::store {
namespace {

using testing::scratch;
namespace fs = std::filesystem;

struct Seen {
    RecordType type;
    std::uint64_t offset;
    Bytes payload;
};

std::vector<Seen> read_all(const fs::path& p, JournalScan* scan = nullptr) {
    std::vector<Seen> v;
    const JournalScan s = scan_journal(p, [&](RecordType t, std::uint64_t off, auto payload) {
        v.push_back({t, off, Bytes(payload.begin(), payload.end())});
    });
    if (scan) *scan = s;
    return v;
}

Bytes payload(std::size_t n, std::uint8_t seed) {
    Bytes b(n);
    for (std::size_t i = 0; i < n; ++i)
        b[i] = static_cast<std::uint8_t>(seed + 7 * i);
    return b;
}

// Three records; returns the offsets (and the size after each).
std::vector<std::uint64_t> write_three(const fs::path& p) {
    Journal j = Journal::create(p);
    std::vector<std::uint64_t> at;
    at.push_back(j.append(RecordType::run_start, payload(40, 1)));
    at.push_back(j.append(RecordType::result, payload(300, 2)));
    at.push_back(j.append(RecordType::error, payload(25, 3)));
    at.push_back(j.size());
    return at;
}

TEST(Journal, RecordsComeBackInOrder) {
    const fs::path p = scratch() / "j";
    const auto at = write_three(p);
    JournalScan scan;
    const auto v = read_all(p, &scan);
    ASSERT_EQ(v.size(), 3u);
    EXPECT_EQ(v[0].type, RecordType::run_start);
    EXPECT_EQ(v[1].type, RecordType::result);
    EXPECT_EQ(v[2].type, RecordType::error);
    for (int i = 0; i < 3; ++i)
        EXPECT_EQ(v[static_cast<std::size_t>(i)].offset, at[static_cast<std::size_t>(i)]);
    EXPECT_EQ(v[1].payload, payload(300, 2));
    EXPECT_EQ(scan.valid_bytes, at[3]);
    EXPECT_EQ(scan.torn_bytes(), 0u);
    EXPECT_EQ(fs::file_size(p), journal_header_size + 3 * record_header_size + 365);
}

TEST(Journal, TornLastRecordAtEveryByteIsDroppedAndAppendsGoOn) {
    const fs::path dir = scratch();
    const fs::path full = dir / "full";
    const auto at = write_three(full);
    std::ifstream in(full, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    // Cut anywhere inside the last record: the first two survive, the third is dropped.
    for (std::uint64_t cut = at[2] + 1; cut < at[3]; ++cut) {
        const fs::path p = dir / "cut";
        fs::remove(p);
        std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(cut));
        JournalScan ro;
        EXPECT_EQ(read_all(p, &ro).size(), 2u) << "cut at " << cut;
        EXPECT_EQ(ro.torn_bytes(), cut - at[2]);
        EXPECT_EQ(fs::file_size(p), cut) << "a read-only scan must not truncate";
        JournalScan scan;
        int seen = 0;
        Journal j = Journal::open(
            p, [&](auto, auto, auto) { ++seen; }, scan);
        EXPECT_EQ(seen, 2);
        EXPECT_EQ(fs::file_size(p), at[2]);
        j.append(RecordType::run_end, payload(10, 9));
        const auto v = read_all(p);
        ASSERT_EQ(v.size(), 3u);
        EXPECT_EQ(v[2].type, RecordType::run_end);
    }
}

TEST(Journal, FlippedByteInLastRecordIsATornTail) {
    const fs::path p = scratch() / "j";
    const auto at = write_three(p);
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(at[3] - 3));
    f.put('\x55');
    f.close();
    JournalScan scan;
    EXPECT_EQ(read_all(p, &scan).size(), 2u);
    EXPECT_EQ(scan.valid_bytes, at[2]);
}

TEST(Journal, ZeroFilledTailIsDropped) {
    // What a file system may leave after a power cut: the size grew, the data did not arrive.
    const fs::path p = scratch() / "j";
    const auto at = write_three(p);
    std::ofstream(p, std::ios::binary | std::ios::app) << std::string(4096, '\0');
    JournalScan scan;
    EXPECT_EQ(read_all(p, &scan).size(), 3u);
    EXPECT_EQ(scan.torn_bytes(), 4096u);
}

TEST(Journal, DamageBeforeValidRecordsIsAnError) {
    const fs::path p = scratch() / "j";
    const auto at = write_three(p);
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(at[1] + record_header_size + 10));
    f.put('\x01');
    f.close();
    try {
        read_all(p);
        FAIL() << "damage accepted";
    } catch (const core::StoreError& e) {
        EXPECT_NE(std::string(e.what()).find("is damaged: an invalid record at byte " +
                                             std::to_string(at[1])),
                  std::string::npos)
            << e.what();
    }
    JournalScan scan;
    EXPECT_THROW(Journal::open(
                     p, [](auto, auto, auto) {}, scan),
                 core::StoreError);
    EXPECT_EQ(fs::file_size(p), at[3]) << "a damaged journal must not be truncated";
}

// A record whose checksum is valid but whose contents the reader cannot use (fuzz_inputs'
// forged journal records): the error names the journal file, the record and its offset, not only
// what the decoder was reading.
TEST(Journal, UnusableRecordIsNamedWithFileAndOffset) {
    const fs::path p = scratch() / "j";
    const auto at = write_three(p);
    try {
        scan_journal(p, [](RecordType t, std::uint64_t, auto) {
            if (t == RecordType::result) throw core::StoreError("journal result record: truncated");
        });
        FAIL() << "the visitor's error was lost";
    } catch (const core::StoreError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("journal '" + p.string() + "' is damaged: its result record at byte " +
                         std::to_string(at[1])),
                  std::string::npos)
            << m;
        EXPECT_NE(m.find("journal result record: truncated"), std::string::npos) << m;
    }
}

TEST(Journal, ForeignAndShortFilesAreRefused) {
    const fs::path dir = scratch();
    std::ofstream(dir / "text") << "this is not a journal, but it is long enough\n";
    std::ofstream(dir / "short") << "HOPPER";
    try {
        read_all(dir / "text");
        FAIL();
    } catch (const core::StoreError& e) {
        EXPECT_NE(std::string(e.what()).find("is not a hopper journal"), std::string::npos);
    }
    try {
        read_all(dir / "short");
        FAIL();
    } catch (const core::StoreError& e) {
        EXPECT_NE(std::string(e.what()).find("too short to be a hopper journal"),
                  std::string::npos);
    }
    EXPECT_THROW(read_all(dir / "missing"), core::StoreError);
}

TEST(Journal, OneWriterAtATime) {
    const fs::path p = scratch() / "j";
    Journal first = Journal::create(p);
    EXPECT_TRUE(first.locked());
    EXPECT_TRUE(journal_locked(p));
    JournalScan scan;
    try {
        Journal::open(
            p, [](auto, auto, auto) {}, scan);
        FAIL() << "second writer accepted";
    } catch (const core::StoreError& e) {
        EXPECT_NE(std::string(e.what()).find("is in use by another `campaign run`"),
                  std::string::npos);
    }
    // Readers are never refused.
    EXPECT_EQ(read_all(p).size(), 0u);
    { Journal released = std::move(first); }
    EXPECT_FALSE(journal_locked(p));
    Journal again = Journal::open(
        p, [](auto, auto, auto) {}, scan);
    EXPECT_TRUE(journal_locked(p));
}

// A one-shot signal between two threads.
class Flag {
  public:
    void raise() {
        {
            std::lock_guard lock(m_);
            up_ = true;
        }
        cv_.notify_all();
    }
    void wait() {
        std::unique_lock lock(m_);
        cv_.wait(lock, [&] { return up_; });
    }

  private:
    std::mutex m_;
    std::condition_variable cv_;
    bool up_ = false;
};

// Issue 14, item 1: two runs creating a new store's journal at once. The interleaving that lost
// everything: A has its new file open, B (a shared temporary name) deleted it and opened its own,
// A linked B's file into place and wrote every record into its deleted one. Made deterministic
// by pausing each creator before it links its file into place.
TEST(Journal, TwoCreatorsAtOnceNeverLeaveAWriterOnADeletedFile) {
    const fs::path dir = scratch();
    const fs::path p = dir / "j";
    Flag a_paused, b_paused, a_done;
    std::string b_error;
    std::thread b([&] {
        a_paused.wait();
        try {
            Journal::create(p, {.before_link = [&] {
                                b_paused.raise();
                                a_done.wait();
                            }});
        } catch (const core::StoreError& e) {
            b_error = e.what();
        }
    });
    std::optional<Journal> a;
    try {
        a.emplace(Journal::create(p, {.before_link = [&] {
                                      a_paused.raise();
                                      b_paused.wait();
                                  }}));
        a->append(RecordType::result, payload(50, 9));
    } catch (...) {
        a_done.raise();
        b.join();
        throw;
    }
    a_done.raise();
    b.join();
    // A's record is in the journal at the path (not in a deleted file), B was refused, and no
    // temporary file is left behind.
    const auto v = read_all(p);
    ASSERT_EQ(v.size(), 1u);
    EXPECT_EQ(v[0].payload, payload(50, 9));
    EXPECT_NE(b_error.find("File exists"), std::string::npos) << b_error;
    int files = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
        ++files;
        EXPECT_EQ(e.path().filename(), "j");
    }
    EXPECT_EQ(files, 1);
}

// The run that loses the race opens the winner's journal: locked while the winner writes it.
TEST(Journal, OpenOrCreateLosingTheRaceFindsTheWinnersJournalInUse) {
    const fs::path p = scratch() / "j";
    Flag b_paused, a_done;
    std::string b_error;
    std::thread b([&] {
        JournalScan scan;
        bool created = true;
        try {
            Journal::open_or_create(p, [](auto, auto, auto) {}, scan, created, {.before_link = [&] {
                                        b_paused.raise();
                                        a_done.wait();
                                    }});
        } catch (const core::StoreError& e) {
            b_error = e.what();
        }
        EXPECT_FALSE(created);
    });
    b_paused.wait();
    JournalScan scan;
    bool created = false;
    Journal a = Journal::open_or_create(
        p, [](auto, auto, auto) {}, scan, created);
    EXPECT_TRUE(created);
    EXPECT_EQ(scan.records, 0u);
    a.append(RecordType::run_start, payload(10, 1));
    a_done.raise();
    b.join();
    EXPECT_NE(b_error.find("is in use by another `campaign run`"), std::string::npos) << b_error;
    EXPECT_EQ(read_all(p).size(), 1u);
}

// Issue 14, item 5: a journal deleted (or replaced) while a run writes it is noticed at the next
// record instead of the run reporting success.
TEST(Journal, DeletedOrReplacedJournalIsNoticedAtTheNextAppend) {
    const fs::path p = scratch() / "j";
    {
        Journal j = Journal::create(p);
        j.append(RecordType::run_start, payload(10, 1));
        fs::remove(p);
        try {
            j.append(RecordType::result, payload(10, 2));
            FAIL() << "append to a deleted journal succeeded";
        } catch (const core::StoreError& e) {
            EXPECT_NE(std::string(e.what()).find("was deleted or replaced"), std::string::npos)
                << e.what();
        }
    }
    Journal j = Journal::create(p);
    fs::rename(p, p.string() + ".moved");
    { Journal other = Journal::create(p); }
    EXPECT_THROW(j.append(RecordType::result, payload(10, 2)), core::StoreError);
}

// Issue 14, item 2: a record that does not fit on the disk (here a file size limit: the same
// failed write) is an error that says so, and the partial record is taken back, so the journal
// ends with its last complete record and the next writer has nothing to drop.
TEST(Journal, ARecordThatDoesNotFitIsTakenBackAndReported) {
    const fs::path p = scratch() / "j";
    { Journal j = Journal::create(p); }
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        ::signal(SIGXFSZ, SIG_IGN);
        const rlimit limit{4096, 4096};
        ::setrlimit(RLIMIT_FSIZE, &limit);
        JournalScan scan;
        Journal j = Journal::open(
            p, [](auto, auto, auto) {}, scan);
        j.append(RecordType::run_start, payload(1000, 1));
        try {
            j.append(RecordType::result, payload(8000, 2));
        } catch (const core::StoreError& e) {
            const std::string m = e.what();
            ::_exit(m.find("File too large") != std::string::npos &&
                            m.find("this record was not written") != std::string::npos
                        ? 0
                        : 3);
        }
        ::_exit(4);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "3: wrong message, 4: no error";
    JournalScan scan;
    const auto v = read_all(p, &scan);
    ASSERT_EQ(v.size(), 1u);
    EXPECT_EQ(scan.torn_bytes(), 0u);
}

}  // namespace
}  // namespace hopper::store
