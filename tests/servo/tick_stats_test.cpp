// Histogram percentiles against known distributions.
#include "hapticd/servo/tick_stats.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace hapticd::servo {
namespace {

// The one rank rule of the histogram and the link diagnosis: ceil(q n), within [1, n].
TEST(ServoTickStats, NearestRankIsTheCeilingOfQTimesNWithinOneToN) {
    EXPECT_EQ(nearest_rank(0.5, 4), 2u);
    EXPECT_EQ(nearest_rank(0.5, 5), 3u);
    EXPECT_EQ(nearest_rank(0.99, 100), 99u);
    EXPECT_EQ(nearest_rank(0.99, 101), 100u);
    EXPECT_EQ(nearest_rank(0.999, 1000), 999u);
    EXPECT_EQ(nearest_rank(0.0, 5), 1u);  // the smallest, not the largest
    EXPECT_EQ(nearest_rank(1.0, 5), 5u);
    EXPECT_EQ(nearest_rank(1.5, 3), 3u);
    EXPECT_EQ(nearest_rank(-1.0, 3), 1u);
    EXPECT_EQ(nearest_rank(0.5, 0), 0u);
}

TEST(ServoTickStats, BucketsTileTheLineWithBoundedRelativeWidth) {
    for (int bucket = 1; bucket < DurationHistogram::kBucketCount; ++bucket) {
        ASSERT_EQ(DurationHistogram::bucket_lower_ns(bucket),
                  DurationHistogram::bucket_upper_ns(bucket - 1));
        const auto lower = DurationHistogram::bucket_lower_ns(bucket);
        ASSERT_EQ(DurationHistogram::bucket_of(lower), bucket);
        ASSERT_EQ(DurationHistogram::bucket_of(DurationHistogram::bucket_upper_ns(bucket) - 1),
                  bucket);
        if (bucket >= DurationHistogram::kExactLimit) {
            const double width =
                static_cast<double>(DurationHistogram::bucket_upper_ns(bucket) - lower);
            ASSERT_LE(width / static_cast<double>(lower), 1.0 / 64.0 + 1e-12);
        }
    }
}

TEST(ServoTickStats, SmallValuesAreExact) {
    DurationHistogram histogram;
    for (int ns = 1; ns <= 100; ++ns) histogram.record(ns);
    EXPECT_EQ(histogram.count(), 100u);
    EXPECT_EQ(histogram.quantile_ns(0.5), 50.0);
    EXPECT_EQ(histogram.quantile_ns(0.99), 99.0);
    EXPECT_EQ(histogram.quantile_ns(1.0), 100.0);
    EXPECT_EQ(histogram.max_ns(), 100);
}

TEST(ServoTickStats, UniformDistributionPercentiles) {
    // 1..100000 ns, each once: the q-quantile is q * 100000 ns; the histogram is within its
    // bucket resolution (1/64 of the value).
    DurationHistogram histogram;
    for (int ns = 1; ns <= 100'000; ++ns) histogram.record(ns);
    for (double q : {0.5, 0.9, 0.99, 0.999}) {
        const double exact = q * 100'000.0;
        EXPECT_NEAR(histogram.quantile_ns(q), exact, exact / 64.0) << q;
    }
    EXPECT_DOUBLE_EQ(histogram.max_us(), 100.0);
    EXPECT_NEAR(histogram.quantile_us(0.5), 50.0, 50.0 / 64.0);
}

TEST(ServoTickStats, ExponentialTailMatchesSortedSample) {
    std::mt19937_64 generator(42);
    std::exponential_distribution<double> latency(1.0 / 20'000.0);  // mean 20 us
    std::vector<std::int64_t> values(200'000);
    DurationHistogram histogram;
    for (auto& value : values) {
        value = static_cast<std::int64_t>(latency(generator));
        histogram.record(value);
    }
    std::sort(values.begin(), values.end());
    for (double q : {0.5, 0.99, 0.999}) {
        const auto index = static_cast<std::size_t>(std::ceil(q * values.size())) - 1;
        const double exact = static_cast<double>(values[index]);
        EXPECT_NEAR(histogram.quantile_ns(q), exact, exact / 64.0 + 1.0) << q;
    }
    EXPECT_EQ(histogram.max_ns(), values.back());
}

TEST(ServoTickStats, EmptyAndOutOfRange) {
    DurationHistogram histogram;
    EXPECT_EQ(histogram.quantile_ns(0.5), 0.0);
    histogram.record(-5);
    histogram.record(std::int64_t{1} << 60);  // lands in the top bucket; max stays exact
    EXPECT_EQ(histogram.count(), 2u);
    EXPECT_EQ(histogram.quantile_ns(0.5), 0.0);
    EXPECT_EQ(histogram.max_ns(), std::int64_t{1} << 60);
}

}  // namespace
}  // namespace hapticd::servo
