#include "hapticd/servo/tick_stats.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace hapticd::servo {

namespace {
constexpr int kSubBucketBits = 6;  // log2(kSubBuckets)
static_assert((1 << kSubBucketBits) == DurationHistogram::kSubBuckets);
static_assert(DurationHistogram::kExactLimit == 2 * DurationHistogram::kSubBuckets);
}  // namespace

int DurationHistogram::bucket_of(std::int64_t duration_ns) noexcept {
    if (duration_ns < kExactLimit) return duration_ns < 0 ? 0 : static_cast<int>(duration_ns);
    const auto value = static_cast<std::uint64_t>(duration_ns);
    // value in [2^(shift+6), 2^(shift+7)): mantissa = value >> shift in [64, 128).
    const int shift = std::bit_width(value) - (kSubBucketBits + 1);
    if (shift > kMaxShift) return kBucketCount - 1;
    const int mantissa = static_cast<int>(value >> shift);
    return kExactLimit + (shift - 1) * kSubBuckets + (mantissa - kSubBuckets);
}

std::int64_t DurationHistogram::bucket_lower_ns(int bucket) noexcept {
    if (bucket < kExactLimit) return bucket;
    const int shift = (bucket - kExactLimit) / kSubBuckets + 1;
    const int mantissa = (bucket - kExactLimit) % kSubBuckets + kSubBuckets;
    return static_cast<std::int64_t>(mantissa) << shift;
}

std::int64_t DurationHistogram::bucket_upper_ns(int bucket) noexcept {
    if (bucket < kExactLimit) return bucket + 1;
    const int shift = (bucket - kExactLimit) / kSubBuckets + 1;
    return bucket_lower_ns(bucket) + (std::int64_t{1} << shift);
}

void DurationHistogram::record(std::int64_t duration_ns) noexcept {
    ++counts_[static_cast<std::size_t>(bucket_of(duration_ns))];
    ++count_;
    max_ns_ = std::max(max_ns_, duration_ns);
}

void DurationHistogram::clear() noexcept {
    counts_.fill(0);
    count_ = 0;
    max_ns_ = 0;
}

double DurationHistogram::quantile_ns(double q) const noexcept {
    if (count_ == 0) return 0.0;
    const std::uint64_t rank = nearest_rank(q, count_);
    std::uint64_t seen = 0;
    for (int bucket = 0; bucket < kBucketCount; ++bucket) {
        seen += counts_[static_cast<std::size_t>(bucket)];
        if (seen >= rank) {
            if (bucket < kExactLimit) return static_cast<double>(bucket);
            const double middle =
                0.5 * static_cast<double>(bucket_lower_ns(bucket) + bucket_upper_ns(bucket) - 1);
            return std::min(middle, static_cast<double>(max_ns_));
        }
    }
    return static_cast<double>(max_ns_);
}

}  // namespace hapticd::servo
