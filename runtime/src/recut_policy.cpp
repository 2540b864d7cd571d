// When the multi-GPU solver re-cuts its parts (weft/backend/recut_policy.h).
#include "weft/backend/recut_policy.h"

#include <algorithm>

namespace weft {

bool RecutPolicy::observe(double imbalance, double threshold) {
    since_recut_ = std::min(since_recut_ + 1, kCooldown);
    if (measure_next_) {
        reached_ = imbalance;
        measure_next_ = false;
    }
    if (!(threshold > 0.0)) {
        above_ = 0;
        return false;
    }
    const double bar = std::max(threshold, kMargin * reached_);
    above_ = imbalance > bar ? above_ + 1 : 0;
    return above_ >= kPersistence && since_recut_ >= kCooldown;
}

void RecutPolicy::recut_done() {
    above_ = 0;
    since_recut_ = 0;
    measure_next_ = true;
}

}  // namespace weft
