#pragma once
/// @file
/// When the multi-GPU solver re-cuts its parts by contact load (docs/multi-gpu.md, "Re-cutting by
/// contact load"). The cut at build time balances rows; contacts gather where the cloth folds, and
/// the part that holds the fold does most of the solve's contact work while the others wait for it.
/// A re-cut rebuilds every part (a fraction of a second to seconds at a million triangles), so it is
/// worth it only for an imbalance that lasts: this policy asks for one after the imbalance has stayed
/// above the bar for several detections in a row, not again for a while after it, and not again for
/// an imbalance the last re-cut could not get below (the granule of the cut and the contacts across
/// it leave some). Host-only, deterministic: the same sequence of imbalances gives the same re-cuts.

namespace weft {

class RecutPolicy {
public:
    /// Detections in a row above the bar before a re-cut.
    static constexpr int kPersistence = 3;
    /// Detections after a re-cut before the next may be asked for.
    static constexpr int kCooldown = 120;
    /// After a re-cut the bar is at least this multiple of the imbalance the re-cut reached (the
    /// first detection after it), so that a cut that cannot do better is not redone at every cooldown.
    static constexpr double kMargin = 1.1;

    /// One detection: `imbalance` is the busiest part's contacts over the mean part's (1 is even),
    /// `threshold` the setting (solver.gpu_rebalance; 0 or less never re-cuts). True when the parts
    /// should be re-cut now; the caller then calls recut_done().
    [[nodiscard]] bool observe(double imbalance, double threshold);
    /// The parts were re-cut: the next detection measures what the cut reached.
    void recut_done();
    /// The imbalance the last re-cut reached (0 before any).
    [[nodiscard]] double reached() const { return reached_; }

private:
    int above_ = 0;
    int since_recut_ = kCooldown;
    bool measure_next_ = false;
    double reached_ = 0.0;
};

}  // namespace weft
