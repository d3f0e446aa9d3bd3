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

}  // namespace
}  // namespace hopper::campaign
