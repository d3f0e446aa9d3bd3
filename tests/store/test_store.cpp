// The store: every field survives journal -> HDF5 -> read back; resume and extension; a writer
// killed at each dangerous moment (mid journal record, mid HDF5 update, mid rebuild, between
// closing the file and the sync record) leaves a store that reopens with nothing lost; damaged
// and foreign files are handled with clear errors.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <fstream>
#include <functional>
#include <tuple>

#include "fixtures.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/analysis.hpp"
#include "hopper/store/journal.hpp"
#include "hopper/store/store.hpp"

namespace hopper::store {
namespace {

using testing::fabricated;
using testing::point;
using testing::result_record;
using testing::run_record;
using testing::scratch;
namespace fs = std::filesystem;

std::string message_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const core::StoreError& e) {
        return e.what();
    }
    return "(no error)";
}

bool contains(const std::string& s, const std::string& part) {
    return s.find(part) != std::string::npos;
}

// The physics bytes (wall clock included: the store must keep them exactly).
std::vector<std::pair<std::string, Bytes>> contents(const std::vector<StoredRealization>& v) {
    std::vector<std::pair<std::string, Bytes>> out;
    for (const auto& s : v)
        out.emplace_back(s.label + "#" + std::to_string(s.record.realization) + " rank " +
                             std::to_string(s.record.rank) + " seed " +
                             std::to_string(s.record.seed),
                         encode_result(s.result));
    std::sort(out.begin(), out.end());
    return out;
}

const PointPlan A = point("D_cm=3 theta_deg=60", 3);
const PointPlan B = point("D_cm=4.5 theta_deg=60", 2);

// A store with one finished run: A#0, A#1, B#0 stored (B#0 failed status), one error on A#2.
fs::path finished_store(const fs::path& dir) {
    const fs::path p = dir / "s.h5";
    Store s(p);
    EXPECT_TRUE(s.is_new());
    s.begin_run(run_record({A, B}));
    s.append(result_record(A, 0, fabricated(0)));
    s.append(result_record(A, 1, fabricated(1, false)));
    s.append(result_record(B, 0, fabricated(3)));  // status failed (3 % 4)
    ErrorRecord e{A.label, 2, A.seeds[2], 2, 1, 1.7e9, "std::bad_alloc"};
    s.append(e);
    s.end_run(RunEndRecord{utc_now(), "complete", 3, 1.0, 0.01});
    return p;
}

// Issue 44: a run that dies (no end record) counts a death for each realization it was
// running (handed out, no result or error yet): killed with it, maybe the cause. A run that
// ends cleanly counts none, and an answer clears the realization.
TEST(Store, ARunThatDiesCountsADeathForWhatItWasRunning) {
    const fs::path p = scratch() / "s.h5";
    const auto hand_out = [](Store& s, const PointPlan& pt, int r, int rank) {
        s.dispatched(
            DispatchRecord{pt.label, r, pt.seeds[static_cast<std::size_t>(r)], rank, 1, 1.7e9});
    };
    {
        Store s(p);
        s.begin_run(run_record({A, B}));
        hand_out(s, A, 0, 1);
        hand_out(s, A, 1, 2);
        hand_out(s, B, 0, 3);
        s.append(result_record(A, 0, fabricated(0)));
        s.append(ErrorRecord{B.label, 0, B.seeds[0], 3, 1, 1.7e9, "std::bad_alloc"});
        // destroyed without end_run: the job was killed while A#1 ran
    }
    {
        const StoreStatus st = read_status(p);
        ASSERT_EQ(st.runs.size(), 1u);
        EXPECT_FALSE(st.runs[0].end.has_value());
        EXPECT_EQ(st.runs[0].died_running, 1);  // A#1
    }
    for (int run = 0; run < 2; ++run) {  // A#1 dies again twice, A#2 once (the second time)
        Store s(p);
        s.begin_run(run_record({A, B}));
        hand_out(s, A, 1, 1);
        if (run == 1) hand_out(s, A, 2, 2);
    }
    {
        Store s(p);
        s.begin_run(run_record({A, B}));
        ASSERT_NE(s.task(A.label, 1), nullptr);
        EXPECT_EQ(s.task(A.label, 0)->deaths, 0);  // answered before the death
        EXPECT_EQ(s.task(A.label, 1)->deaths, 3);
        EXPECT_EQ(s.task(A.label, 2)->deaths, 1);
        EXPECT_EQ(s.task(B.label, 0)->deaths, 0);  // its exception answered it
        EXPECT_EQ(s.task(B.label, 0)->state, TaskState::error);
        // A run that ends cleanly with a realization handed out (stopped: its state saved or
        // thrown away) counts no death.
        hand_out(s, B, 1, 1);
        s.end_run(RunEndRecord{utc_now(), "interrupted by SIGTERM", 0, 1.0, 0.01});
    }
    Store s(p);
    s.begin_run(run_record({A, B}));
    EXPECT_EQ(s.task(B.label, 1)->deaths, 0);
    EXPECT_EQ(s.task(A.label, 1)->deaths, 3);  // kept across runs (journal replay)
    const StoreStatus st = s.status();
    ASSERT_EQ(st.runs.size(), 5u);
    EXPECT_EQ(st.runs[1].died_running, 1);
    EXPECT_EQ(st.runs[2].died_running, 2);
    EXPECT_EQ(st.runs[3].died_running, 0);  // ended
    // A realization handed out that no run planned is refused before it is journaled.
    const std::string msg = message_of([&] {
        s.dispatched(DispatchRecord{"D_cm=9", 0, 1, 1, 1, 1.7e9});
    });
    EXPECT_TRUE(contains(msg, "which no run planned")) << msg;
    s.end_run(RunEndRecord{utc_now(), "complete", 0, 1.0, 0.01});
    EXPECT_EQ(read_status(p).runs[4].died_running, 0);
}

// Opens the store, expects its first note to contain `note`, and runs an empty run (which
// rebuilds the HDF5 file when it is not in step); the realizations read back afterwards.
std::vector<std::pair<std::string, Bytes>> reopen_expecting(const fs::path& p,
                                                            const std::string& note) {
    {
        Store s(p);
        EXPECT_FALSE(s.notes().empty());
        if (!s.notes().empty()) {
            EXPECT_TRUE(contains(s.notes()[0], note)) << s.notes()[0];
        }
        s.begin_run(run_record({A, B}));
        s.end_run(RunEndRecord{utc_now(), "complete", 0, 1.0, 0.01});
    }
    return contents(read_realizations(p));
}

TEST(Store, EveryFieldSurvivesJournalAndHdf5) {
    const fs::path p = finished_store(scratch());
    const auto from_h5 = read_realizations(p);
    const auto from_journal = read_journal_realizations(p);
    ASSERT_EQ(from_h5.size(), 3u);
    EXPECT_EQ(contents(from_h5), contents(from_journal));
    // Against what was appended, field by field through the encoding (wall clock included).
    EXPECT_EQ(encode_result(from_h5[0].result), result_record(A, 0, fabricated(0)).result);
    EXPECT_EQ(encode_result(from_h5[1].result), result_record(A, 1, fabricated(1, false)).result);
    EXPECT_FALSE(from_h5[1].result.empty_time.has_value());
    EXPECT_EQ(from_h5[2].label, B.label);
    EXPECT_EQ(from_h5[2].record.task_seconds, 0.5);
    EXPECT_EQ(from_h5[1].record.finished_unix, 1.7e9 + 1);
    EXPECT_EQ(from_h5[0].record.rank, 1);
}

// Fields: a point whose scene switches them on (the HDF5 view copies its window settings).
const PointPlan F = point("D_cm=4.5 theta_deg=60 fields.kernel=gaussian", 3,
                          "hopper.width_m=0.2\nfields.window_s=0.02\nfields.cell_dlarge=2\n"
                          "fields.sample_interval_s=0.001\nfields.start_s=0.5\nfields.end_s=unset\n"
                          "fields.kernel=gaussian\n");

fs::path store_with_fields(const fs::path& dir) {
    const fs::path p = dir / "s.h5";
    Store s(p);
    s.begin_run(run_record({A, F}));
    s.append(result_record(F, 0, testing::with_fields(fabricated(0), 1, 5, 4)));  // row 0
    s.append(result_record(A, 0, fabricated(1)));                                 // row 1
    s.append(result_record(F, 2, testing::with_fields(fabricated(2), 3, 5, 4)));  // row 2
    s.end_run(RunEndRecord{utc_now(), "complete", 3, 1.0, 0.01});
    return p;
}

TEST(Store, FieldsSurviveJournalHdf5AndRebuild) {
    const fs::path p = store_with_fields(scratch());
    const auto from_h5 = read_realizations(p);
    ASSERT_EQ(from_h5.size(), 3u);
    EXPECT_EQ(contents(from_h5), contents(read_journal_realizations(p)));  // fields included
    ASSERT_TRUE(from_h5[0].result.fields.has_value());
    EXPECT_FALSE(from_h5[1].result.fields.has_value());
    EXPECT_EQ(encode_result(from_h5[2].result),
              result_record(F, 2, testing::with_fields(fabricated(2), 3, 5, 4)).result);
    // One group per realization with fields, named by its row.
    EXPECT_EQ(derived_group_members(p, "fields"), (std::vector<std::string>{"0", "2"}));
    EXPECT_EQ(derived_group_members(p, "fields/0").size(), 12u);  // 10 maps + the outline
    const DerivedDataset mean = read_derived_dataset(p, "fields/2/mean_vy");
    EXPECT_EQ(mean.shape, (std::vector<std::uint64_t>{4, 5}));  // ny x nx
    EXPECT_EQ(mean.units, "m/s");
    EXPECT_EQ(std::get<std::vector<double>>(mean.values), from_h5[2].result.fields->mean[1]);
    const DerivedDataset n = read_derived_dataset(p, "fields/0/windows");
    EXPECT_EQ(std::get<std::vector<std::int64_t>>(n.values), from_h5[0].result.fields->windows);
    EXPECT_EQ(read_derived_dataset(p, "fields/0/m2_pressure").units, "(m g)^2");
    // Rebuilt from the journal: the same view.
    fs::remove(p);
    {
        Store s(p);
        s.begin_run(run_record({A, F}));
        s.append(result_record(F, 1, fabricated(4)));  // row 3, without fields
        s.end_run(RunEndRecord{utc_now(), "complete", 1, 1.0, 0.01});
    }
    EXPECT_EQ(contents(read_realizations(p)), contents(read_journal_realizations(p)));
    EXPECT_EQ(derived_group_members(p, "fields"), (std::vector<std::string>{"0", "2"}));
    // Appending to the file in step (no rebuild) adds to the existing group.
    {
        const PointPlan F4 = point(F.label, 4, F.scene);
        Store s(p);
        EXPECT_TRUE(s.notes().empty());
        s.begin_run(run_record({A, F4}));
        s.append(result_record(F4, 3, testing::with_fields(fabricated(5), 1, 5, 4)));  // row 4
        s.end_run(RunEndRecord{utc_now(), "complete", 1, 1.0, 0.01});
    }
    EXPECT_EQ(derived_group_members(p, "fields"), (std::vector<std::string>{"0", "2", "4"}));
    EXPECT_EQ(contents(read_realizations(p)), contents(read_journal_realizations(p)));
}

TEST(Store, AvalanchesAndArchesSurviveJournalHdf5AndRebuild) {
    const fs::path p = scratch() / "sci.h5";
    const auto r0 = testing::with_science(fabricated(2), 1);  // 2 jams: arches of 0 and 4 disks
    const auto r1 = testing::with_science(fabricated(5), 2);  // 2 jams
    {
        Store s(p);
        s.begin_run(run_record({A, B}));
        s.append(result_record(A, 0, r0));
        s.append(result_record(A, 1, fabricated(4)));  // as stored before issue 13: none
        s.append(result_record(A, 2, testing::with_fields(r1, 2, 3, 2)));
        s.end_run(RunEndRecord{utc_now(), "complete", 3, 1.0, 0.01});
    }
    const auto check = [&](const std::vector<StoredRealization>& got) {
        ASSERT_EQ(got.size(), 3u);
        EXPECT_EQ(encode_result(got[0].result), result_record(A, 0, r0).result);
        EXPECT_TRUE(got[1].result.avalanche_sizes.empty());
        EXPECT_TRUE(got[1].result.arches.empty());
        EXPECT_EQ(got[2].result.arches.size(), 2u);
        EXPECT_EQ(got[2].result.arches[1].ids.size(), 4u);
        EXPECT_EQ(got[2].result.avalanche_sizes, r1.avalanche_sizes);
    };
    check(read_realizations(p));
    check(read_journal_realizations(p));
    fs::remove(p);  // rebuilt from the journal by the next run
    {
        Store s(p);
        s.begin_run(run_record({A, B}));
        s.end_run(RunEndRecord{utc_now(), "complete", 0, 1.0, 0.01});
    }
    check(read_realizations(p));
}

TEST(Store, WithoutFieldsThereIsNoFieldsGroup) {
    const fs::path p = finished_store(scratch());
    EXPECT_TRUE(derived_group_members(p, "fields").empty());
    for (const auto& r : read_journal_realizations(p))
        EXPECT_FALSE(r.result.fields.has_value());
}

TEST(Store, StatusCountsDoneFailedErrorsAndPending) {
    const fs::path p = finished_store(scratch());
    const StoreStatus s = read_status(p);
    EXPECT_EQ(s.total, 5);
    EXPECT_EQ(s.done, 2);
    EXPECT_EQ(s.failed, 2);  // B#0 (status failed) and A#2 (exception)
    EXPECT_EQ(s.errors, 1);
    EXPECT_EQ(s.pending, 1);
    ASSERT_EQ(s.points.size(), 2u);
    EXPECT_EQ(s.points[0].done, 2);
    EXPECT_EQ(s.points[1].failed, 1);
    ASSERT_EQ(s.failures.size(), 2u);
    EXPECT_EQ(s.failures[0].reason, "std::bad_alloc");
    EXPECT_TRUE(s.failures[0].exception);
    EXPECT_FALSE(s.failures[1].exception);
    EXPECT_TRUE(s.hdf5_in_step);
    EXPECT_FALSE(s.writer_active);
    ASSERT_EQ(s.runs.size(), 1u);
    ASSERT_TRUE(s.runs[0].end.has_value());
    EXPECT_EQ(s.runs[0].stored, 3);
}

TEST(Store, ResumeExtendsThePlanAndKeepsEverything) {
    const fs::path p = finished_store(scratch());
    Store s(p);
    EXPECT_FALSE(s.is_new());
    EXPECT_TRUE(s.notes().empty()) << s.notes().front();
    ASSERT_NE(s.task(A.label, 0), nullptr);
    EXPECT_EQ(s.task(A.label, 0)->state, TaskState::done);
    EXPECT_EQ(s.task(A.label, 2)->state, TaskState::error);
    EXPECT_EQ(s.task(B.label, 0)->state, TaskState::failed);
    const PointPlan A5 = point(A.label, 5);
    const PointPlan C = point("D_cm=6 theta_deg=60", 1);
    s.begin_run(run_record({A5, C}));  // B not in this sweep: it stays in the plan
    EXPECT_EQ(s.plan().points.size(), 3u);
    EXPECT_EQ(s.plan().find(A.label)->realizations(), 5);
    s.append(result_record(A5, 2, fabricated(5)));
    s.append(result_record(A5, 4, fabricated(6)));
    s.append(result_record(C, 0, fabricated(7)));
    s.end_run(RunEndRecord{utc_now(), "complete", 3, 1.0, 0.01});
    const StoreStatus st = read_status(p);
    EXPECT_EQ(st.total, 8);
    EXPECT_EQ(st.done, 4);
    EXPECT_EQ(st.failed, 2);   // B#0, C#0 (status failed); A#2's exception is superseded
    EXPECT_EQ(st.pending, 2);  // A#3, B#1
    EXPECT_EQ(st.runs.size(), 2u);
    EXPECT_EQ(contents(read_realizations(p)), contents(read_journal_realizations(p)));
    EXPECT_EQ(read_realizations(p).size(), 6u);
}

// Issue 29: a target campaign's plan lists its first round and its limit; each round's
// allotment record extends it, so the journal and the plan grow with the rounds, never to the
// limit, and a round recorded again (a resume) writes nothing.
TEST(Store, AllotmentsGrowThePlanRoundByRoundNotToItsLimit) {
    const fs::path p = scratch() / "s.h5";
    const PointPlan all = point("D_cm=3 theta_deg=60", 1000);
    PointPlan first = all;
    first.seeds.resize(2);
    first.limit = 1000000;
    const auto seeds = [&](int from, int to) {
        return std::vector<std::uint64_t>(all.seeds.begin() + from, all.seeds.begin() + to);
    };
    {
        Store s(p);
        s.begin_run(run_record({first}));
        EXPECT_LT(fs::file_size(journal_path(p)), 1000u) << "the plan lists no limit's seeds";
        s.append(result_record(all, 0, fabricated(0)));
        s.append(result_record(all, 1, fabricated(1)));
        const AllotmentRecord round2{{PointAllotment{all.label, 0, seeds(0, 4)}}};
        s.allot(round2);
        const auto after_round = fs::file_size(journal_path(p));
        s.allot(round2);  // again: nothing new
        s.allot(AllotmentRecord{{PointAllotment{all.label, 2, seeds(2, 3)}}});  // inside it
        EXPECT_EQ(fs::file_size(journal_path(p)), after_round);
        EXPECT_EQ(s.plan().points[0].realizations(), 4);
        EXPECT_EQ(s.plan().points[0].limit, 1000000);
        const StoreStatus st = s.status();
        EXPECT_EQ(st.points[0].planned, 4);
        EXPECT_EQ(st.points[0].limit, 1000000);
        EXPECT_EQ(st.pending, 2);
        EXPECT_TRUE(
            contains(message_of([&] {
                         s.allot(AllotmentRecord{{PointAllotment{all.label, 5, seeds(5, 6)}}});
                     }),
                     "leaves a gap"));
        s.append(result_record(all, 2, fabricated(2)));
        s.end_run(RunEndRecord{utc_now(), "interrupted by SIGTERM", 3, 1.0, 0.01});
    }
    // Replayed from the journal: the same plan and counts; a resume's first-round plan does not
    // shrink it.
    StoreStatus st = read_status(p);
    ASSERT_EQ(st.plan.points.size(), 1u);
    EXPECT_EQ(st.plan.points[0].seeds, seeds(0, 4));
    EXPECT_EQ(st.plan.points[0].limit, 1000000);
    EXPECT_EQ(st.total, 4);
    EXPECT_EQ(st.done + st.failed, 3);
    EXPECT_EQ(st.pending, 1);
    {
        Store s(p);
        s.begin_run(run_record({first}));
        EXPECT_EQ(s.plan().points[0].realizations(), 4);
        s.allot(AllotmentRecord{{PointAllotment{all.label, 4, seeds(4, 6)}}});
        s.append(result_record(all, 5, fabricated(5)));
        s.end_run(RunEndRecord{utc_now(), "complete", 1, 1.0, 0.01});
    }
    st = read_status(p);
    EXPECT_EQ(st.plan.points[0].seeds, seeds(0, 6));
    EXPECT_EQ(st.points[0].planned, 6);
    EXPECT_EQ(contents(read_realizations(p)), contents(read_journal_realizations(p)));
    EXPECT_LT(fs::file_size(journal_path(p)), 20000u);
}

TEST(Store, StatusWorksWhileARunWrites) {
    const fs::path p = scratch() / "s.h5";
    Store s(p);
    s.begin_run(run_record({A}));
    s.append(result_record(A, 1, fabricated(1)));
    const StoreStatus st = read_status(p);
    EXPECT_TRUE(st.writer_active);
    EXPECT_FALSE(st.hdf5_in_step);
    EXPECT_EQ(st.done, 1);
    EXPECT_EQ(st.pending, 2);
    // A second writer is refused while the first holds the store.
    EXPECT_TRUE(contains(message_of([&] { Store other(p); }), "in use by another"));
}

// Issue 27: readers during a run. A snapshot taken while a Store writes (its HDF5 file open,
// the journal locked, the last record half written) is a closed store of its own holding every
// realization the journal held; the writer goes on and ends as if nothing had happened.
TEST(Store, ASnapshotWhileARunWritesHoldsEverythingStoredAndDisturbsNothing) {
    const fs::path dir = scratch();
    const fs::path p = dir / "s.h5";
    Store s(p);
    s.begin_run(run_record({A, B}));
    s.append(result_record(A, 0, fabricated(0)));
    s.append(result_record(B, 1, fabricated(1)));
    // A record being appended: half of one more, as a reader may find it.
    {
        std::ofstream j(journal_path(p), std::ios::binary | std::ios::app);
        const char half[8] = {'H', 'J', 'R', 'C', 2, 0, 0, 0};
        j.write(half, sizeof half);
    }
    const Snapshot snap = write_snapshot(p, dir / "view" / "v.h5");
    EXPECT_TRUE(snap.writer_active);
    EXPECT_EQ(snap.realizations, 2);
    const StoreStatus view = read_status(dir / "view" / "v.h5");
    EXPECT_FALSE(view.writer_active);
    EXPECT_TRUE(view.hdf5_in_step);
    EXPECT_EQ(view.done, 2);
    EXPECT_EQ(contents(read_realizations(dir / "view" / "v.h5")),
              contents(read_journal_realizations(p)));
    // A snapshot never overwrites anything.
    EXPECT_TRUE(contains(message_of([&] { write_snapshot(p, dir / "view" / "v.h5"); }), "exists"));
    EXPECT_TRUE(contains(message_of([&] { write_snapshot(p, p); }), "exists"));
    // The writer was not disturbed (the half record above stands for one of its own appends
    // in progress: taken back, since only the writer appends).
    fs::resize_file(journal_path(p), fs::file_size(journal_path(p)) - 8);
    s.append(result_record(A, 1, fabricated(2)));
    s.end_run(RunEndRecord{utc_now(), "complete", 3, 1.0, 0.01});
    EXPECT_EQ(read_realizations(p).size(), 3u);
    EXPECT_EQ(contents(read_realizations(p)), contents(read_journal_realizations(p)));
    // The snapshot kept the moment it was taken.
    EXPECT_EQ(read_realizations(dir / "view" / "v.h5").size(), 2u);
}

TEST(Store, ASnapshotNeedsTheJournal) {
    const fs::path dir = scratch();
    EXPECT_TRUE(
        contains(message_of([&] { write_snapshot(dir / "none.h5", dir / "v.h5"); }), "no journal"));
}

TEST(Store, WriterThatNeverClosedIsRebuiltFromTheJournal) {
    const fs::path p = scratch() / "s.h5";
    {
        Store s(p, StoreOptions{0.0, "", 0, true, {}, {}});
        s.begin_run(run_record({A, B}));
        s.append(result_record(A, 0, fabricated(0)));
        s.append(result_record(B, 1, fabricated(1)));
        // destroyed without end_run: as if the master died
    }
    Store s(p);
    ASSERT_EQ(s.notes().size(), 1u);
    EXPECT_TRUE(contains(s.notes()[0], "not in step with the journal")) << s.notes()[0];
    s.begin_run(run_record({A, B}));
    s.append(result_record(A, 1, fabricated(2)));
    s.end_run(RunEndRecord{utc_now(), "complete", 1, 1.0, 0.01});
    EXPECT_EQ(read_realizations(p).size(), 3u);
    EXPECT_EQ(contents(read_realizations(p)), contents(read_journal_realizations(p)));
}

// Build item 5 of issue 14: damage inside an HDF5 file that was closed in step (a disk error
// later) was read as it is. Here a point's label is altered in the file's bytes (same size):
// the checksum recorded in the sync record exposes it, and the file is rebuilt from the journal
// without being opened.
TEST(Store, AFileDamagedAfterItWasClosedIsRebuiltFromTheJournal) {
    const fs::path p = finished_store(scratch());
    const auto before = contents(read_journal_realizations(p));
    std::string bytes;
    {
        std::ifstream in(p, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    const std::string label = B.label, altered = "D_cm=4.7 theta_deg=60";
    int replaced = 0;
    for (auto at = bytes.find(label); at != std::string::npos; at = bytes.find(label, at + 1)) {
        bytes.replace(at, altered.size(), altered);
        ++replaced;
    }
    ASSERT_GT(replaced, 0) << "the label is not stored as plain bytes";
    std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
    EXPECT_EQ(reopen_expecting(p, "does not match the checksum"), before);
    Store again(p);
    EXPECT_TRUE(again.notes().empty()) << again.notes()[0];
}

// Stores written before checksums have sync records without one: still in step, not rebuilt.
TEST(Store, ASyncRecordWithoutAChecksumStillCountsAsInStep) {
    const fs::path p = finished_store(scratch());
    const fs::path j = journal_path(p);
    std::uint64_t last = 0;
    SyncRecord sync;
    scan_journal(j, [&](RecordType t, std::uint64_t off, auto payload) {
        if (t == RecordType::sync) {
            last = off;
            sync = decode_sync(payload);
        }
    });
    ASSERT_TRUE(sync.file.has_value());
    fs::resize_file(j, last);
    {
        JournalScan scan;
        Journal journal = Journal::open(
            j, [](auto, auto, auto) {}, scan);
        sync.file.reset();
        journal.append(RecordType::sync, encode(sync));
    }
    Store s(p);
    EXPECT_TRUE(s.notes().empty()) << s.notes()[0];
}

// `campaign analyze` replaces /analysis in a closed file: it records the file's new checksum,
// so the next run finds the file in step (no rebuild, /analysis kept).
TEST(Store, ReplacingADerivedGroupKeepsTheFileInStep) {
    const fs::path p = finished_store(scratch());
    DerivedGroup g;
    g.name = "analysis";
    g.attributes.emplace_back("created", "now");
    DerivedGroup sub;
    sub.name = "points";
    g.groups.push_back(sub);
    write_derived_group(p, g);
    write_derived_group(p, g);  // twice: each replacement records its own checksum
    {
        Store s(p);
        EXPECT_TRUE(s.notes().empty()) << s.notes()[0];
    }
    EXPECT_EQ(derived_group_members(p, "analysis"), std::vector<std::string>{"points"});
}

TEST(Store, DamagedOrMissingHdf5IsRebuilt) {
    const fs::path dir = scratch();
    const fs::path p = finished_store(dir);
    const auto before = contents(read_journal_realizations(p));
    fs::resize_file(p, fs::file_size(p) / 2);  // keeps the HDF5 signature, loses the rest
    EXPECT_EQ(reopen_expecting(p, "damaged"), before);
    fs::remove(p);
    EXPECT_EQ(reopen_expecting(p, "missing"), before);
}

TEST(Store, ForeignFilesAndAMissingJournalGiveClearErrors) {
    const fs::path dir = scratch();
    std::ofstream(dir / "notes.h5") << "some text file\n";
    EXPECT_TRUE(contains(message_of([&] { Store s(dir / "notes.h5"); }),
                         "exists and is not a hopper store (not an HDF5 file)"));
    EXPECT_TRUE(
        contains(message_of([&] { read_status(dir / "notes.h5"); }), "is not a hopper store"));
    const fs::path p = finished_store(dir);
    fs::remove(journal_path(p));
    EXPECT_TRUE(contains(message_of([&] { Store s(p); }), "has no journal"));
    EXPECT_EQ(read_realizations(p).size(), 3u) << "the file alone stays readable";
    EXPECT_TRUE(contains(message_of([&] { read_status(dir / "nothing.h5"); }), "no store at"));
    // A journal beside a file that is not a store: the file is not overwritten.
    const fs::path q = dir / "q.h5";
    { Store s(q); }
    std::ofstream(q) << "not hdf5";
    EXPECT_TRUE(contains(message_of([&] { Store s(q); }), "although its journal"));
}

// Issue 14, item 5: `--store DIR` said "not an HDF5 file".
TEST(Store, ADirectoryIsCalledADirectory) {
    const fs::path dir = scratch();
    fs::create_directories(dir / "d.h5");
    for (const fs::path& p : {dir / "d.h5", dir}) {
        const std::string m = message_of([&] { Store s(p); });
        EXPECT_TRUE(contains(m, "'" + p.string() + "' is a directory")) << m;
        EXPECT_TRUE(contains(m, (p / "store.h5").string())) << m;
        EXPECT_TRUE(contains(message_of([&] { read_status(p); }), "is a directory"));
    }
    EXPECT_TRUE(fs::is_empty(dir / "d.h5")) << "nothing was created inside";
}

// Issue 14, item 1: after the race a journal held only its header while the HDF5 file held every
// result, and the next run rebuilt (emptied) the file from that journal. A file holding more
// than its journal knows is refused and left alone.
TEST(Store, AFileHoldingMoreThanItsJournalIsRefusedNotRebuilt) {
    const fs::path p = finished_store(scratch());
    fs::remove(journal_path(p));
    { Journal j = Journal::create(journal_path(p)); }
    const std::string m = message_of([&] { Store s(p); });
    EXPECT_TRUE(contains(m, "holds 3 realizations but its journal")) << m;
    EXPECT_TRUE(contains(m, "knows only 0")) << m;
    EXPECT_EQ(read_realizations(p).size(), 3u) << "the file was left alone";
}

// A journal that exists but cannot be reached (here a symlink loop; also a directory without
// permission) is not "missing" (found by fuzz_inputs: the store said "has no journal" and would
// have tried to create one).
TEST(Store, JournalThatCannotBeReachedIsNotCalledMissing) {
    const fs::path p = finished_store(scratch());
    const fs::path j = journal_path(p);
    fs::remove(j);
    fs::create_symlink(j.filename(), j);  // points to itself
    const std::string opened = message_of([&] { Store s(p); });
    EXPECT_TRUE(contains(opened, "cannot access the store's journal '" + j.string() + "'"))
        << opened;
    EXPECT_TRUE(contains(opened, "symbolic links")) << opened;
    const std::string status = message_of([&] { read_status(p); });
    EXPECT_TRUE(contains(status, "cannot access the store's journal")) << status;
    EXPECT_TRUE(fs::is_symlink(j)) << "nothing was created or replaced";
}

// Runs `work` in a child process that is expected to die of SIGKILL (a crash injected by the
// store), and returns whether it did.
bool dies_of_sigkill(const std::function<void()>& work) {
    const pid_t pid = fork();
    if (pid == 0) {
        try {
            work();
        } catch (...) {
            _exit(3);
        }
        _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
}

class CrashPoint : public ::testing::TestWithParam<std::pair<const char*, int>> {};

TEST_P(CrashPoint, KilledWriterLosesNothingCountedAsDone) {
    const auto [where, n] = GetParam();
    const fs::path p = scratch() / "s.h5";
    {  // one finished run first, so that the HDF5 file exists and is in step
        Store s(p);
        s.begin_run(run_record({A, B}));
        s.append(result_record(A, 0, fabricated(0)));
        s.end_run(RunEndRecord{utc_now(), "complete", 1, 1.0, 0.01});
    }
    if (std::string(where) == "rebuild") fs::remove(p);  // force a rebuild in the child
    ASSERT_TRUE(dies_of_sigkill([&, where = where, n = n] {
        Store s(p, StoreOptions{0.0, where, n, true, {}, {}});
        s.begin_run(run_record({A, B}));
        s.append(result_record(A, 1, fabricated(1)));
        s.append(result_record(A, 2, fabricated(2)));
        s.append(result_record(B, 0, fabricated(4)));
        s.end_run(RunEndRecord{utc_now(), "complete", 3, 1.0, 0.01});
    })) << "the crash was not injected at "
        << where;
    // Reopen: whatever finished before the kill is there exactly once; the rest runs again.
    const std::vector<std::tuple<const PointPlan*, int, int>> work = {
        {&A, 1, 1}, {&A, 2, 2}, {&B, 0, 4}};  // (point, realization, fabricated k)
    {
        Store s(p);
        s.begin_run(run_record({A, B}));
        for (const auto& [pt, r, k] : work)
            if (s.task(pt->label, r)->state == TaskState::pending)
                s.append(result_record(*pt, r, fabricated(k)));
        s.end_run(RunEndRecord{utc_now(), "complete", 0, 1.0, 0.01});
    }
    std::vector<StoredRealization> expected(1);
    expected[0].label = A.label;
    expected[0].record = result_record(A, 0, fabricated(0));
    expected[0].result = decode_result(expected[0].record.result);
    for (const auto& [pt, r, k] : work) {
        StoredRealization e;
        e.label = pt->label;
        e.record = result_record(*pt, r, fabricated(k));
        e.result = decode_result(e.record.result);
        expected.push_back(e);
    }
    const auto h5 = read_realizations(p);
    EXPECT_EQ(contents(h5), contents(expected));
    EXPECT_EQ(contents(read_journal_realizations(p)), contents(expected));
    const StoreStatus st = read_status(p);
    EXPECT_EQ(st.done + st.failed, 4);
    EXPECT_TRUE(st.hdf5_in_step);
}

INSTANTIATE_TEST_SUITE_P(
    Store, CrashPoint,
    ::testing::Values(std::pair{"journal", 1},  // mid run_start record
                      std::pair{"journal", 3},  // mid second result record
                      std::pair{"journal", 5},  // mid run_end record
                      std::pair{"hdf5", 2},     // partial HDF5 update after the 2nd result
                      std::pair{"rebuild", 1},  // rebuilt file written, not yet renamed
                      std::pair{"close", 1}),   // file closed, sync record not yet written
    [](const auto& param_info) {
        return std::string(param_info.param.first) + "_" + std::to_string(param_info.param.second);
    });

}  // namespace
}  // namespace hopper::store
