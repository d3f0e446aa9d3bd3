// `campaign submit --dry-run`: the chain of allocations against the cost estimate (issue 27:
// 241.7 core-hours estimated, 11 allocations x 1 h x 2 workers = 22 worker-hours, no word).

#include <gtest/gtest.h>

#include "cli/submit.hpp"

namespace hopper::cli {
namespace {

bool contains(const std::string& s, const std::string& part) {
    return s.find(part) != std::string::npos;
}

TEST(SubmitChain, TheIssuesDefaultChainCannotFinishItsEstimate) {
    // Defaults: 1 + 10 allocations of 1:00:00 (120 s of them the drain), --ntasks 2, the
    // master's slot shared: 2 workers of 1 thread.
    const Chain chain{11, 3600, 120, 2, 2, 1, false};
    const std::string w = chain_warning(chain, 241.7 * 3600, 520.0);
    EXPECT_TRUE(contains(w, "warning: the chain cannot finish the estimate")) << w;
    EXPECT_TRUE(contains(w, "11 allocation(s) x 1:00:00 x 2 worker(s)")) << w;
    // Needed with 20 % to spare: 241.7 h x 1.2 = 1044144 s over 11 x 3480 s = 27.3 -> 28
    // workers; or over 11 x 2 workers: 47461 s + 120 s = 13:13:02 -> 13:14:00.
    EXPECT_TRUE(contains(w, "--ntasks 28 (same --time)")) << w;
    EXPECT_TRUE(contains(w, "--time 13:14:00 (same --ntasks)")) << w;
    // The suggestions hold the estimate.
    EXPECT_EQ(chain_warning(Chain{11, 3600, 120, 28, 28, 1, false}, 241.7 * 3600, 520.0), "");
    EXPECT_EQ(
        chain_warning(Chain{11, 13 * 3600 + 14 * 60, 120, 2, 2, 1, false}, 241.7 * 3600, 520.0),
        "");
}

TEST(SubmitChain, RanksOfSeveralThreadsAndTheMastersOwnRank) {
    // 4 ranks of 8 threads, one of them the master's: 24 workers; 100 worker-hours in 2
    // allocations of 2 h: 120 h x 1.2 / (2 x 7080 s) = 30.5 -> 31 workers = 4 ranks + 1.
    const Chain chain{2, 7200, 120, 24, 4, 8, true};
    const std::string w = chain_warning(chain, 100 * 3600, 60.0);
    EXPECT_TRUE(contains(w, "--ntasks 5 (same --time)")) << w;
}

TEST(SubmitChain, ARealizationLongerThanAnAllocationIsNamed) {
    const Chain chain{11, 1800, 120, 100, 100, 1, false};
    const std::string w = chain_warning(chain, 3600.0, 2400.0);
    EXPECT_FALSE(contains(w, "warning")) << w;
    EXPECT_TRUE(contains(w, "one realization is expected to take 40m00s")) << w;
}

}  // namespace
}  // namespace hopper::cli
