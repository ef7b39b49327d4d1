// check_exact checks its sweep on two threads (tune/exact_model.cpp): the verdict, the worst
// case and the count are those of one pass in order. A class search (tune/class_check.cpp)
// probes and climbs as jobs that one thread per core takes from a queue: its verdict is the
// same every run. Under ThreadSanitizer (this test is in HAPTICD_THREADED_TESTS) the threads
// share nothing but the queue.
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "hapticd/tune/class_check.hpp"
#include "hapticd/tune/class_proof.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "operator_classes.hpp"

namespace hapticd::tune {
namespace {

TEST(ExactSweepThreads, TheWorstCaseIsTheOneOfAPassInOrder) {
    const theory::DeviceModel pen{0.1, 2.0};
    const double rate_hz = 1000.0;
    for (const double stiffness : {1500.0, 4200.0}) {
        const theory::SpringDamperCoupling coupling{stiffness, 0.5};
        const std::vector<OperatorModel> operators = default_operator_sweep(pen, rate_hz);
        std::vector<EnvironmentModel> environments = default_environment_sweep(pen);
        environments.resize(12);
        const ExactCheck check = check_exact(pen, coupling, rate_hz, operators, environments, 0.0);
        ASSERT_GE(operators.size() * environments.size(), 2000U);  // worth the second thread
        // One pass in order, as the check did before it had threads.
        double worst = -1.0;
        const OperatorModel* worst_operator = nullptr;
        const EnvironmentModel* worst_environment = nullptr;
        for (const OperatorModel& h : operators) {
            for (const EnvironmentModel& e : environments) {
                const double r =
                    closed_loop_poles(pen, coupling, rate_hz, h, e, 0.0).spectral_radius;
                if (r > worst) worst = r, worst_operator = &h, worst_environment = &e;
            }
        }
        EXPECT_EQ(check.cases_checked, static_cast<int>(operators.size() * environments.size()));
        EXPECT_DOUBLE_EQ(check.worst_spectral_radius, worst);
        EXPECT_EQ(check.worst_operator.describe(), worst_operator->describe());
        EXPECT_EQ(check.worst_environment.describe(), worst_environment->describe());
        EXPECT_EQ(check.stable, stiffness < 3000.0) << check.worst_spectral_radius;
    }
}

TEST(ClassSearchThreads, TheVerdictIsTheSameEveryRunAndAgreesWithTheProof) {
    // The pen-grip class at its proven limit (b_c 0.5, no delay): stable, so every probe and
    // every climb runs; 3 % past it the search finds a member that grows, and stops at the
    // first job in order that decided it, however the threads took the jobs.
    const theory::DeviceModel pen{0.1, 2.0};
    const double rate_hz = 1000.0;
    StabilityAssumption assumption;
    assumption.operators = testing::pen_grip_class();
    const ClassProver prover(pen, *assumption.operators, rate_hz, 0.0);
    theory::SpringDamperCoupling coupling{0.0, 0.5};
    coupling.stiffness_n_per_m = prover.stiffness_limit(coupling, 0.0).stiffness_n_per_m;
    const ExactCheck first = check_exact(pen, coupling, rate_hz, assumption, 0.0);
    const ExactCheck second = check_exact(pen, coupling, rate_hz, assumption, 0.0);
    EXPECT_TRUE(first.stable) << first.worst_spectral_radius;
    EXPECT_EQ(first.cases_checked, second.cases_checked);
    EXPECT_EQ(first.worst_spectral_radius, second.worst_spectral_radius);
    EXPECT_EQ(first.worst_operator.describe(), second.worst_operator.describe());
    EXPECT_EQ(first.worst_environment.describe(), second.worst_environment.describe());
    coupling.stiffness_n_per_m *= 1.03;
    const ExactCheck past = check_exact(pen, coupling, rate_hz, assumption, 0.0);
    const ExactCheck again = check_exact(pen, coupling, rate_hz, assumption, 0.0);
    EXPECT_FALSE(past.stable);
    EXPECT_GT(past.worst_spectral_radius, 1.0 + kDecisiveGrowthPerTick);
    EXPECT_EQ(past.cases_checked, again.cases_checked);
    EXPECT_EQ(past.worst_spectral_radius, again.worst_spectral_radius);
    EXPECT_EQ(past.worst_operator.describe(), again.worst_operator.describe());
}

TEST(ClassSearchThreads, TheVerdictKeepsItsDelayWhicheverJobFoundTheWorst) {
    // The merged verdict states the delay it assumed, whichever job's climb found the worst
    // case: the pen-grip class at b_c 0.5, half its proof with one period of delay and at its
    // proof with one and a half (both stable: every climb runs). A share of the search that
    // started from an empty check once lost it there (0 periods).
    const theory::DeviceModel pen{0.1, 2.0};
    const double rate_hz = 1000.0;
    StabilityAssumption assumption;
    assumption.operators = testing::pen_grip_class();
    for (const auto& [delay_periods, factor] : {std::pair{1.0, 0.5}, std::pair{1.5, 1.0}}) {
        const ClassProver prover(pen, *assumption.operators, rate_hz, delay_periods);
        theory::SpringDamperCoupling coupling{0.0, 0.5};
        coupling.stiffness_n_per_m =
            factor * prover.stiffness_limit(coupling, 0.0).stiffness_n_per_m;
        const ExactCheck check = check_exact(pen, coupling, rate_hz, assumption, delay_periods);
        EXPECT_TRUE(check.stable) << delay_periods;
        EXPECT_EQ(check.delay_periods, delay_periods) << factor << " x the proof";
    }
}

}  // namespace
}  // namespace hapticd::tune
