#include "beslam/motion/hungarian.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

using beslam::motion::solveAssignment;

namespace {

double total(const std::vector<double>& c, int cols, const std::vector<int>& a) {
  double s = 0;
  for (size_t r = 0; r < a.size(); ++r)
    if (a[r] >= 0) s += c[r * cols + a[r]];
  return s;
}

// Exhaustive minimum over every assignment of min(rows, cols) pairs.
double bruteForce(const std::vector<double>& c, int rows, int cols) {
  const bool wide = rows <= cols;
  const int n = wide ? rows : cols, m = wide ? cols : rows;
  std::vector<int> perm(m);
  std::iota(perm.begin(), perm.end(), 0);
  double best = 1e300;
  do {
    double s = 0;
    for (int i = 0; i < n; ++i) s += wide ? c[i * cols + perm[i]] : c[perm[i] * cols + i];
    best = std::min(best, s);
  } while (std::next_permutation(perm.begin(), perm.end()));
  return best;
}

}  // namespace

TEST(Hungarian, SmallKnownCase) {
  const std::vector<double> c = {4, 1, 3,  //
                                 2, 0, 5,  //
                                 3, 2, 2};
  const auto a = solveAssignment(c, 3, 3);
  EXPECT_EQ(a, (std::vector<int>{1, 0, 2}));
  EXPECT_DOUBLE_EQ(total(c, 3, a), 5.0);
}

TEST(Hungarian, EmptyAndDegenerate) {
  EXPECT_TRUE(solveAssignment({}, 0, 3).empty());
  EXPECT_EQ(solveAssignment({}, 2, 0), (std::vector<int>{-1, -1}));
  EXPECT_EQ(solveAssignment({7.0}, 1, 1), (std::vector<int>{0}));
  EXPECT_THROW(solveAssignment({1, 2, 3}, 2, 2), std::invalid_argument);
  EXPECT_THROW(solveAssignment({1, std::numeric_limits<double>::infinity()}, 1, 2), std::invalid_argument);
}

TEST(Hungarian, MatchesBruteForceOnRandomMatrices) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0, 10);
  for (auto [rows, cols] : std::vector<std::pair<int, int>>{{5, 5}, {6, 6}, {4, 7}, {7, 4}, {1, 6}, {6, 1}}) {
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<double> c(rows * cols);
      for (double& x : c) x = std::floor(u(rng));  // integers: many ties
      const auto a = solveAssignment(c, rows, cols);
      ASSERT_EQ(static_cast<int>(a.size()), rows);
      std::vector<int> used;
      for (int x : a)
        if (x >= 0) used.push_back(x);
      ASSERT_EQ(static_cast<int>(used.size()), std::min(rows, cols));
      std::sort(used.begin(), used.end());
      ASSERT_EQ(std::adjacent_find(used.begin(), used.end()), used.end()) << "a column assigned twice";
      EXPECT_NEAR(total(c, cols, a), bruteForce(c, rows, cols), 1e-9) << rows << "x" << cols;
    }
  }
}
