// CostEta (campaign/report.hpp): the time left weighted by each task's cost.
#include "hopper/campaign/report.hpp"

#include <gtest/gtest.h>

namespace hopper::campaign {
namespace {

TEST(CostEta, UsesThePriorUntilSomethingIsMeasured) {
    CostEta eta(2, 1e-6);
    eta.add_pending(1e6, 4);  // 4 tasks of 1e6 particle-steps: 4 s of work at the prior
    EXPECT_FALSE(eta.measured());
    EXPECT_DOUBLE_EQ(eta.seconds_left(), 2.0);  // on 2 workers
}

TEST(CostEta, WeighsPendingTasksByCostNotByCount) {
    // The expensive tasks run first: after the one expensive task, three cheap ones are left.
    // A count of realizations would predict 3 x its 10 s; the cost weighting predicts 3 x 1 s.
    CostEta eta(1, 1e-6);
    eta.add_pending(1e7);
    eta.add_pending(1e6, 3);
    eta.finished(1e7, 10.0);
    EXPECT_TRUE(eta.measured());
    EXPECT_DOUBLE_EQ(eta.seconds_per_cost(), 1e-6);
    EXPECT_DOUBLE_EQ(eta.seconds_left(), 3.0);
    eta.finished(1e6, 2.0);  // slower than expected: the rate is corrected
    EXPECT_NEAR(eta.seconds_per_cost(), 12.0 / 1.1e7, 1e-18);
    EXPECT_NEAR(eta.seconds_left(), 2e6 * 12.0 / 1.1e7, 1e-12);
    eta.finished(1e6, 1.0, 2);
    EXPECT_DOUBLE_EQ(eta.seconds_left(), 0.0);
}

// Issue 27: a 16-realization full-size run on 16 workers whose first two realizations ended
// early (arrested after 2 minutes of a 10-minute cost) printed "ETA 2m10s" for 14 running
// realizations that needed about 8 more minutes each: the mean of the first finished ones
// stood for all. Now the speed is measured on what those two computed (a fifth of their
// expected particle-steps), and each running realization counts with what it has left.
TEST(CostEta, RunningRealizationsCountWithWhatTheyHaveLeft) {
    const double cost = 1.2e10;  // particle-steps of one full-size realization
    CostEta eta(16, 50e-9);      // prior: 600 s per realization
    eta.add_pending(cost, 16);
    // Two arrested after 120 s each, having computed 2.4e9 particle-steps each (50 ns each).
    eta.finished(cost, 240.0, 2, true, 2 * 2.4e9);
    EXPECT_DOUBLE_EQ(eta.seconds_per_cost(), 50e-9);
    std::vector<RunningCost> running(14, RunningCost{cost, 120.0});
    // Each has 600 - 120 = 480 s left; 14 x 480 s over 16 workers is 420 s, but no worker can
    // finish another's realization: the longest remainder, 480 s.
    EXPECT_DOUBLE_EQ(eta.seconds_left(running), 480.0);
    // Before: the speed from the expected costs of the two (240 s for 2.4e10), and the 14
    // running ones counted in full as pending: 14 x 1.2e10 x 1e-8 / 16 = 105 s, the "ETA 2m10s"
    // the issue saw (plus its rounding to the progress interval).
    CostEta before(16, 50e-9);
    before.add_pending(cost, 16);
    before.finished(cost, 240.0, 2);
    EXPECT_DOUBLE_EQ(before.seconds_left(), 105.0);
}

TEST(CostEta, ARealizationPastItsExpectedTimeStillCountsAsRunning) {
    CostEta eta(2, 1e-6);
    eta.add_pending(1e6, 3);  // 1 s each at the prior
    // Two running: one half done, one at 5 s of its expected 1 s (at least a twentieth left).
    const std::vector<RunningCost> running{{1e6, 0.5}, {1e6, 5.0}};
    // queued 1 s + 0.5 s + 0.05 s over 2 workers = 0.775 s.
    EXPECT_DOUBLE_EQ(eta.seconds_left(running), 0.775);
}

}  // namespace
}  // namespace hopper::campaign
