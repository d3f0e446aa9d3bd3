// ending_of (campaign/run_end.hpp): the verdict of a run from what the master reports and what
// the sweep still lacks. The drain cases are the fault of 2026-11-26 (a SIGUSR1 that the last
// realization outlived made a complete run "interrupted", exit 4) and its first fix's fault (a
// SIGTERM that raced the last realization became "complete", exit 0).
#include "hopper/campaign/run_end.hpp"

#include <gtest/gtest.h>

namespace hopper::campaign {
namespace {

MasterReport stopped_by(const char* reason, bool stop_sent_to_running, int interrupted = 0) {
    MasterReport r;
    r.stopped = true;
    r.stop_reason = reason;
    r.stopped_running = stop_sent_to_running;
    r.interrupted = interrupted;
    return r;
}

TEST(RunEnding, NoStopIsCompleteOrHasFailures) {
    EXPECT_EQ(ending_of(MasterReport{}, Outcome{0, 0}, false), Ending::complete);
    EXPECT_EQ(ending_of(MasterReport{}, Outcome{0, 2}, false), Ending::with_failures);
    EXPECT_EQ(ending_of(MasterReport{}, Outcome{0, 0}, true), Ending::complete);
}

TEST(RunEnding, ADrainTheLastRealizationOutlivedIsComplete) {
    EXPECT_EQ(ending_of(stopped_by("SIGUSR1", false), Outcome{0, 0}, false), Ending::complete);
    // ... with failed realizations stored before it: finished, with failures.
    EXPECT_EQ(ending_of(stopped_by("SIGUSR1", false), Outcome{0, 1}, false), Ending::with_failures);
}

TEST(RunEnding, ADrainThatLeftWorkIsAnInterruption) {
    EXPECT_EQ(ending_of(stopped_by("SIGUSR1", false), Outcome{3, 0}, false), Ending::interrupted);
    EXPECT_EQ(ending_of(stopped_by("SIGUSR1", false, 1), Outcome{0, 0}, false),
              Ending::interrupted);
}

TEST(RunEnding, AStopSentToRunningRealizationsStaysAStop) {
    // SIGTERM reached the workers, but the last realization ended before it: still a stop.
    EXPECT_EQ(ending_of(stopped_by("SIGTERM", true), Outcome{0, 0}, false), Ending::interrupted);
}

TEST(RunEnding, AnyStopOfATargetCampaignIsAnInterruption) {
    // Its rounds decide what is due: nothing left now does not mean the target is met.
    EXPECT_EQ(ending_of(stopped_by("SIGUSR1", false), Outcome{0, 0}, true), Ending::interrupted);
}

TEST(RunEnding, IdenticalEarlyFailuresStopEarly) {
    MasterReport r;
    r.fail_fast = "3 realizations failed at the fill";
    EXPECT_EQ(ending_of(r, Outcome{10, 3}, false), Ending::stopped_early);
}

}  // namespace
}  // namespace hopper::campaign
