// When the multi-GPU solver re-cuts its parts by contact load (weft/backend/recut_policy.h): only
// after the imbalance lasts, not again during the cooldown, not again for an imbalance the last
// re-cut could not get below, never with the setting at 0.
#include <gtest/gtest.h>

#include "weft/backend/recut_policy.h"

namespace weft {
namespace {

/// Detections until the policy asks for a re-cut at a steady `imbalance` (−1: not within `limit`).
int detections_until_recut(RecutPolicy& policy, double imbalance, double threshold, int limit) {
    for (int d = 1; d <= limit; ++d)
        if (policy.observe(imbalance, threshold)) return d;
    return -1;
}

TEST(RecutPolicy, ALastingImbalanceRecutsAfterThePersistence) {
    RecutPolicy policy;
    EXPECT_EQ(detections_until_recut(policy, 1.6, 1.25, 100), RecutPolicy::kPersistence);
}

TEST(RecutPolicy, AnImbalanceBelowTheBarOrBrokenOffNeverRecuts) {
    RecutPolicy policy;
    EXPECT_EQ(detections_until_recut(policy, 1.2, 1.25, 1000), -1);
    for (int d = 0; d < 100; ++d) {
        // Above the bar, but never for kPersistence detections in a row.
        for (int k = 0; k + 1 < RecutPolicy::kPersistence; ++k) EXPECT_FALSE(policy.observe(2.0, 1.25));
        EXPECT_FALSE(policy.observe(1.0, 1.25));
    }
}

TEST(RecutPolicy, ZeroTurnsItOff) {
    RecutPolicy policy;
    EXPECT_EQ(detections_until_recut(policy, 10.0, 0.0, 1000), -1);
}

TEST(RecutPolicy, TheCooldownAndWhatTheLastRecutReachedHoldTheNext) {
    RecutPolicy policy;
    ASSERT_EQ(detections_until_recut(policy, 1.6, 1.25, 100), RecutPolicy::kPersistence);
    policy.recut_done();
    // The re-cut reached 1.3 (above the bar of 1.25): that imbalance, even lasting, is not redone.
    EXPECT_EQ(detections_until_recut(policy, 1.3, 1.25, 1000), -1);
    EXPECT_DOUBLE_EQ(policy.reached(), 1.3);
    // Worse than the reached 1.3 by more than the margin: re-cut, but not within the cooldown.
    RecutPolicy again;
    ASSERT_EQ(detections_until_recut(again, 1.6, 1.25, 100), RecutPolicy::kPersistence);
    again.recut_done();
    EXPECT_FALSE(again.observe(1.3, 1.25));  // what this re-cut reached
    const int d = detections_until_recut(again, 1.8, 1.25, 1000);
    EXPECT_EQ(1 + d, RecutPolicy::kCooldown) << "after the cooldown, not sooner";
}

}  // namespace
}  // namespace weft
