// store::merge_stores (campaign merge, issue 43): every realization of the inputs once and byte
// for byte (wall clock, rank and attempt of the first input's copy included), every run once,
// error records kept; copies that differ in physics, points of other physics and another seed
// refused with nothing written. End to end with real runs: tests/campaign/merge.sh.

#include <gtest/gtest.h>

#include <functional>

#include "fixtures.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/store.hpp"

namespace hopper::store {
namespace {

using testing::fabricated;
using testing::point;
using testing::result_record;
using testing::run_record;
using testing::scratch;
namespace fs = std::filesystem;

const PointPlan P = point("D_cm=3 theta_deg=60", 3);
const PointPlan Q = point("D_cm=4.5 theta_deg=60", 3);

// The whole record of each stored realization, sorted (the store keeps them exactly).
std::vector<std::pair<std::string, Bytes>> records(const std::vector<StoredRealization>& v) {
    std::vector<std::pair<std::string, Bytes>> out;
    for (const auto& s : v) {
        ResultRecord r = s.record;
        r.result = encode_result(s.result);
        out.emplace_back(s.label + "#" + std::to_string(r.realization), encode(r));
    }
    std::sort(out.begin(), out.end());
    return out;
}

// A store with one run of `points` storing `results`, and an error record on the first point.
fs::path store_of(const fs::path& p, const std::vector<PointPlan>& points,
                  const std::vector<ResultRecord>& results, std::uint64_t seed = 7) {
    Store s(p);
    s.begin_run(run_record(points, seed));
    for (const auto& r : results)
        s.append(r);
    s.append(ErrorRecord{points[0].label, 2, points[0].seeds[2], 2, 1, 1.7e9, "std::bad_alloc"});
    s.end_run(RunEndRecord{utc_now(), "complete", static_cast<int>(results.size()), 1.0, 0.01});
    return p;
}

RunInfo merge_run() {
    RunInfo r;
    r.start_time = utc_now();
    r.command = "campaign merge (test)";
    return r;
}

std::string refusal(const std::function<void()>& f) {
    try {
        f();
    } catch (const core::ConfigError& e) {
        return e.what();
    }
    return "(no refusal)";
}

TEST(Merge, DisjointPointsGiveTheUnionRecordForRecord) {
    const fs::path dir = scratch();
    const fs::path a =
        store_of(dir / "a.h5", {P},
                 {result_record(P, 0, fabricated(0)), result_record(P, 1, fabricated(1, false))});
    const fs::path b =
        store_of(dir / "b.h5", {Q},
                 {result_record(Q, 0, fabricated(3)), result_record(Q, 1, fabricated(4))});
    const MergeReport rep = merge_stores({a, b}, dir / "c.h5", merge_run());
    EXPECT_EQ(rep.realizations, 4);
    EXPECT_EQ(rep.identical_copies, 0);
    EXPECT_EQ(rep.points, 2);
    EXPECT_EQ(rep.runs, 2);
    auto want = records(read_journal_realizations(a));
    for (auto& r : records(read_journal_realizations(b)))
        want.push_back(r);
    std::sort(want.begin(), want.end());
    EXPECT_EQ(records(read_journal_realizations(dir / "c.h5")), want);
    EXPECT_EQ(records(read_realizations(dir / "c.h5")), want);
    const StoreStatus st = read_status(dir / "c.h5");
    EXPECT_TRUE(st.hdf5_in_step);
    ASSERT_EQ(st.runs.size(), 3u);  // a's, b's, the merge's
    EXPECT_EQ(st.runs[2].info.command, "campaign merge (test)");
    EXPECT_EQ(st.runs[2].end->reason, "merged 2 stores");
    EXPECT_EQ(st.errors, 2);  // both error records kept (P#2, Q#2 in error)
    EXPECT_EQ(st.plan.seed, 7u);
}

TEST(Merge, ACopyInBothIsStoredOnceAsTheFirstInputHasIt) {
    const fs::path dir = scratch();
    // The same physics on another rank with another wall clock: the same realization.
    ResultRecord other = result_record(P, 0, fabricated(0), 5);
    other.task_seconds = 99.0;
    const fs::path a = store_of(dir / "a.h5", {P}, {result_record(P, 0, fabricated(0))});
    const fs::path b = store_of(dir / "b.h5", {P}, {other, result_record(P, 1, fabricated(1))});
    const MergeReport rep = merge_stores({a, b}, dir / "c.h5", merge_run());
    EXPECT_EQ(rep.realizations, 2);
    EXPECT_EQ(rep.identical_copies, 1);
    const auto got = read_journal_realizations(dir / "c.h5");
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(got[0].record.rank, 1);  // a's copy
    EXPECT_EQ(records(read_realizations(dir / "c.h5")), records(got));
    // A store with itself: nothing twice, its run once.
    const MergeReport self = merge_stores({b, b}, dir / "d.h5", merge_run());
    EXPECT_EQ(self.realizations, 2);
    EXPECT_EQ(self.identical_copies, 2);
    EXPECT_EQ(self.runs, 1);
    EXPECT_EQ(self.shared_runs, 1);
    EXPECT_EQ(records(read_journal_realizations(dir / "d.h5")),
              records(read_journal_realizations(b)));
    EXPECT_EQ(read_status(dir / "d.h5").errors, 1);
}

TEST(Merge, DifferingCopiesPhysicsAndSeedsAreRefusedWithNothingWritten) {
    const fs::path dir = scratch();
    const fs::path a = store_of(dir / "a.h5", {P}, {result_record(P, 0, fabricated(0))});
    const fs::path b = store_of(dir / "b.h5", {P}, {result_record(P, 0, fabricated(6))});
    const fs::path c = dir / "c.h5";
    std::string m = refusal([&] { merge_stores({a, b}, c, merge_run()); });
    EXPECT_NE(m.find("realization 0 of point 'D_cm=3 theta_deg=60' differs between"),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("nothing was written"), std::string::npos) << m;
    EXPECT_FALSE(fs::exists(c));
    EXPECT_FALSE(fs::exists(journal_path(c)));

    const PointPlan other = point(P.label, 3, "hopper.width_m=0.09\nscene_of=x\n");
    const fs::path o = store_of(dir / "o.h5", {other}, {result_record(other, 1, fabricated(1))});
    m = refusal([&] { merge_stores({a, o}, c, merge_run()); });
    EXPECT_NE(m.find("point 'D_cm=3 theta_deg=60' has other physics"), std::string::npos) << m;
    EXPECT_NE(m.find("hopper.width_m = 0.08 in"), std::string::npos) << m;
    EXPECT_FALSE(fs::exists(c));

    const fs::path s = store_of(dir / "s.h5", {Q}, {result_record(Q, 0, fabricated(3))}, 8);
    m = refusal([&] { merge_stores({a, s}, c, merge_run()); });
    EXPECT_NE(m.find("the campaign seeds differ"), std::string::npos) << m;
    m = refusal([&] { merge_stores({a}, a, merge_run()); });
    EXPECT_NE(m.find("exists; a merge writes a new store"), std::string::npos) << m;
}

}  // namespace
}  // namespace hopper::store
