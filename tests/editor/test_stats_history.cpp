// The editor's step history (weft/editor/stats_history.h): what its warning banner counts.
#include <gtest/gtest.h>

#include "weft/editor/stats_history.h"

namespace weft::editor {
namespace {

TEST(StatsHistory, CountsEachKindOfTroubleAndClears) {
    StatsHistory h;
    StepStats clean, capped, nan, runaway, gained, stretched, torn;
    clean.max_stretch = 1.02;
    stretched.max_stretch = kOverstretch - 0.5;  // stretched, not torn
    torn.max_stretch = 30.0;
    capped.cg_not_converged = 2;
    nan.non_finite = true;
    runaway.runaway_solves = 1;
    gained.energy_gained = 1;
    for (const StepStats* s : {&clean, &capped, &nan, &runaway, &runaway, &stretched, &torn, &gained}) h.record(*s);
    EXPECT_EQ(h.steps, 8);
    EXPECT_EQ(h.overstretched_steps, 1);
    EXPECT_EQ(h.not_converged_steps, 1);
    EXPECT_EQ(h.non_finite_steps, 1);
    EXPECT_EQ(h.runaway_steps, 2);
    EXPECT_EQ(h.energy_gained_steps, 1);
    EXPECT_EQ(h.last.energy_gained, 1);
    h.clear();
    EXPECT_EQ(h.steps, 0);
    EXPECT_EQ(h.runaway_steps, 0);
    EXPECT_EQ(h.overstretched_steps, 0);
    EXPECT_EQ(h.non_finite_steps, 0);
}

}  // namespace
}  // namespace weft::editor
