// Per-tick statistics without allocation: log-linear histograms of durations in nanoseconds
// (exact below 128 ns, then 64 sub-buckets per power of two: every recorded value is within
// 1.6 % of its bucket's representative), plus counters. Written by the servo thread only;
// read after the loop has stopped (the live status goes through ServoLoop::status()).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "hapticd/servo/nearest_rank.hpp"

namespace hapticd::servo {

class DurationHistogram {
  public:
    static constexpr int kExactLimit = 128;  ///< values below are their own bucket
    static constexpr int kSubBuckets = 64;   ///< per power of two above kExactLimit
    static constexpr int kMaxShift = 36;     ///< up to ~2^43 ns (about 2.4 hours)
    static constexpr int kBucketCount = kExactLimit + kMaxShift * kSubBuckets;

    /// Records one duration; negative values count as 0, huge ones land in the top bucket.
    void record(std::int64_t duration_ns) noexcept;
    void clear() noexcept;

    std::uint64_t count() const noexcept { return count_; }
    /// Exact largest value recorded, ns (0 when empty).
    std::int64_t max_ns() const noexcept { return max_ns_; }
    /// The q-quantile (0 <= q <= 1) in ns: the representative (midpoint) of the bucket holding
    /// the ceil(q count)-th smallest value, capped at max_ns(). 0 when empty.
    double quantile_ns(double q) const noexcept;
    double quantile_us(double q) const noexcept { return quantile_ns(q) * 1e-3; }
    double max_us() const noexcept { return static_cast<double>(max_ns_) * 1e-3; }

    static int bucket_of(std::int64_t duration_ns) noexcept;
    /// [lower, upper) of a bucket, ns.
    static std::int64_t bucket_lower_ns(int bucket) noexcept;
    static std::int64_t bucket_upper_ns(int bucket) noexcept;

  private:
    std::array<std::uint64_t, kBucketCount> counts_{};
    std::uint64_t count_ = 0;
    std::int64_t max_ns_ = 0;
};

struct TickStats {
    std::uint64_t ticks = 0;           ///< ticks run
    std::uint64_t overruns = 0;        ///< ticks that started after their deadline had passed
    std::uint64_t missed_periods = 0;  ///< deadlines skipped by those overruns
    std::uint64_t read_timeouts = 0;   ///< reads that gave no sample
    std::uint64_t solver_not_converged = 0;
    std::uint64_t saturated_ticks = 0;
    std::uint64_t overspeed_ticks = 0;
    std::uint64_t passivity_control_ticks = 0;
    std::uint64_t link_recoveries = 0;    ///< link-fault latches cleared by LinkRecovery
    std::uint64_t intervals_unknown = 0;  ///< samples with no known time since the last one
    double max_force_n = 0.0;             ///< largest |F| commanded (vector norm)
    /// The overrun that exhausted the budget (kFaultOverrunBudget): how late that tick woke,
    /// the periods it missed and the overrunning ticks in a row; all 0 until one does.
    std::int64_t budget_overrun_late_ns = 0;
    std::int64_t budget_overrun_missed_periods = 0;
    int budget_overrun_consecutive = 0;
    DurationHistogram wake_latency;  ///< actual wake - deadline
    DurationHistogram compute;       ///< wake to command written

    void clear() noexcept { *this = TickStats{}; }
};

}  // namespace hapticd::servo
