// The rate–distortion choice of the residual steps (codec/encode/rate_distortion.h): the Lagrangian choice per
// subband, and the searches for a distortion or a bit budget, checked against every combination of the measured steps.
#include <cstddef>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "encode/rate_distortion.h"

namespace segmorph {
namespace {

SubbandCurve curve(std::vector<double> distortion, std::vector<double> bits) {
  SubbandCurve c;
  for (size_t i = 0; i < distortion.size(); ++i) c.step.push_back(double(i + 1));
  c.distortion = std::move(distortion);
  c.bits = std::move(bits);
  return c;
}

// Random curves as measurement gives them: distortion rising with the step, bits falling, not convex.
void random_curves(std::mt19937& random, SubbandCurve (&curves)[3]) {
  std::uniform_real_distribution<double> jump(0.1, 10), steps(3, 8);
  for (SubbandCurve& c : curves) {
    c = SubbandCurve();
    const size_t count = size_t(steps(random));
    double distortion = jump(random), bits = 100 * jump(random);
    for (size_t i = 0; i < count; ++i) {
      c.step.push_back(double(i + 1));
      c.distortion.push_back(distortion);
      c.bits.push_back(bits);
      distortion += jump(random) * jump(random);
      bits = std::max(0.0, bits - 10 * jump(random) * jump(random));
    }
  }
}

struct Totals {
  double distortion, bits;
};

Totals totals(const SubbandCurve (&curves)[3], const StepChoice& choice) {
  Totals t{0, 0};
  for (int axis = 0; axis < 3; ++axis) {
    t.distortion += curves[axis].distortion[choice.index[axis]];
    t.bits += curves[axis].bits[choice.index[axis]];
  }
  return t;
}

// Calls f(distortion, bits) for every combination of one step per subband.
template <typename F>
void every_combination(const SubbandCurve (&curves)[3], F f) {
  for (size_t i = 0; i < curves[0].step.size(); ++i)
    for (size_t j = 0; j < curves[1].step.size(); ++j)
      for (size_t k = 0; k < curves[2].step.size(); ++k)
        f(curves[0].distortion[i] + curves[1].distortion[j] + curves[2].distortion[k],
          curves[0].bits[i] + curves[1].bits[j] + curves[2].bits[k]);
}

TEST(RateDistortion, LagrangianChoiceIsPerSubband) {
  const SubbandCurve curves[3] = {curve({1, 2, 4, 8}, {80, 50, 30, 20}), curve({1, 3, 9}, {60, 40, 5}),
                                  curve({2, 2.5, 6}, {90, 70, 10})};
  const StepChoice fine = choose_steps(curves, 0);  // distortion alone: the first of each (ties keep the first)
  EXPECT_EQ(fine.index[0], 0u);
  EXPECT_EQ(fine.index[1], 0u);
  EXPECT_EQ(fine.index[2], 0u);
  EXPECT_DOUBLE_EQ(fine.distortion, 4);
  EXPECT_DOUBLE_EQ(fine.bits, 230);
  const StepChoice coarse = choose_steps(curves, 1e9);  // bits alone
  EXPECT_EQ(coarse.index[0], 3u);
  EXPECT_EQ(coarse.index[1], 2u);
  EXPECT_EQ(coarse.index[2], 2u);
  EXPECT_DOUBLE_EQ(coarse.bits, 35);
  // λ = 0.1: D + R/10 is 9, 7, 7, 10 in x; 7, 7, 9.5 in y; 11, 9.5, 7 in z.
  const StepChoice middle = choose_steps(curves, 0.1);
  EXPECT_EQ(middle.index[0], 1u);
  EXPECT_EQ(middle.index[1], 0u);
  EXPECT_EQ(middle.index[2], 2u);
  const Totals t = totals(curves, middle);
  EXPECT_DOUBLE_EQ(middle.distortion, t.distortion);
  EXPECT_DOUBLE_EQ(middle.bits, t.bits);
}

// A point above the lower convex hull of its curve is never a Lagrangian choice; the search still finds it when it
// is the cheapest that meets the target.
TEST(RateDistortion, FindsTheCheapestChoiceTheLagrangianMisses) {
  const SubbandCurve curves[3] = {curve({0, 5, 10}, {100, 80, 0}), curve({0}, {0}), curve({0}, {0})};
  for (double lambda : {0.0, 0.01, 0.1, 0.2, 1.0, 100.0})
    EXPECT_NE(choose_steps(curves, lambda).index[0], 1u) << lambda;  // (5, 80) is above the hull
  const StepChoice choice = steps_for_distortion(curves, 6);
  EXPECT_EQ(choice.index[0], 1u);
  EXPECT_DOUBLE_EQ(choice.bits, 80);
  EXPECT_EQ(steps_for_bits(curves, 90).index[0], 1u);
}

TEST(RateDistortion, SearchesAgreeWithEveryCombination) {
  std::mt19937 random(7);
  for (int trial = 0; trial < 300; ++trial) {
    SCOPED_TRACE(trial);
    SubbandCurve curves[3];
    random_curves(random, curves);
    // A budget somewhere in the range of each figure: the best of the other figure among the combinations within it.
    for (bool bound_bits : {false, true}) {
      double least = std::numeric_limits<double>::infinity(), most = 0;
      every_combination(curves, [&](double d, double b) {
        least = std::min(least, bound_bits ? b : d), most = std::max(most, bound_bits ? b : d);
      });
      const double budget = least + (most - least) * std::uniform_real_distribution<>(0, 1)(random);
      double best = std::numeric_limits<double>::infinity();
      every_combination(curves, [&](double d, double b) {
        if ((bound_bits ? b : d) <= budget) best = std::min(best, bound_bits ? d : b);
      });
      const StepChoice choice = bound_bits ? steps_for_bits(curves, budget) : steps_for_distortion(curves, budget);
      const Totals t = totals(curves, choice);
      EXPECT_LE(bound_bits ? t.bits : t.distortion, budget);
      EXPECT_DOUBLE_EQ(bound_bits ? choice.distortion : choice.bits, best);
    }
  }
}

// A target no combination meets gives the nearest: the least distorted choice, or the fewest bits.
TEST(RateDistortion, UnreachableTargetsGiveTheNearestChoice) {
  const SubbandCurve curves[3] = {curve({1, 2}, {50, 10}), curve({1, 4}, {40, 20}), curve({3, 5}, {30, 1})};
  const StepChoice finest = steps_for_distortion(curves, 1);  // the least is 5
  EXPECT_DOUBLE_EQ(finest.distortion, 5);
  const StepChoice smallest = steps_for_bits(curves, 10);  // the fewest is 31
  EXPECT_DOUBLE_EQ(smallest.bits, 31);
}

}  // namespace
}  // namespace segmorph
