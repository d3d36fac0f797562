// SPDX-License-Identifier: BSD-3-Clause
// The built-in kd-tree against a brute force that computes distances the same
// way: identical indices, distances and tie order (lower index first).
extern "C" {
#include "dacpo_kdtree.h"
}

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <thread>
#include <utility>
#include <vector>

namespace {

std::vector<std::pair<double, int32_t>>
bruteForce(const std::vector<double>& xyz, const double q[3], size_t k)
{
  size_t n = xyz.size() / 3;
  std::vector<std::pair<double, int32_t>> all(n);
  for (size_t i = 0; i < n; ++i) {
    double dx = q[0] - xyz[3 * i], dy = q[1] - xyz[3 * i + 1],
           dz = q[2] - xyz[3 * i + 2];
    all[i] = {dx * dx + dy * dy + dz * dz, static_cast<int32_t>(i)};
  }
  std::sort(all.begin(), all.end()); // (distance, index): ties to the lower index
  all.resize(std::min(k, n));
  return all;
}

dacpo_kdtree*
build(const std::vector<double>& xyz)
{
  dacpo_kdtree* t = nullptr;
  dacpo_err err{};
  EXPECT_EQ(dacpo_kdtree_build(xyz.data(), xyz.size() / 3, &t, &err), DACPO_OK)
      << err.msg;
  return t;
}

// Queries at every `stride`-th point and at random positions; checks exact equality.
void
expectMatchesBruteForce(const std::vector<double>& xyz,
                        size_t k,
                        size_t stride,
                        uint32_t seed)
{
  dacpo_kdtree* t = build(xyz);
  ASSERT_NE(t, nullptr);
  size_t n = xyz.size() / 3;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  std::vector<int32_t> idx(k + 1, -7);
  std::vector<double> d(k + 1, -7.0);
  for (size_t s = 0; s < n + 40; s += (s < n ? stride : 1)) {
    double q[3];
    if (s < n) {
      q[0] = xyz[3 * s];
      q[1] = xyz[3 * s + 1];
      q[2] = xyz[3 * s + 2];
    }
    else {
      q[0] = u(rng);
      q[1] = u(rng);
      q[2] = u(rng);
    }
    auto expect = bruteForce(xyz, q, k);
    size_t got = dacpo_kdtree_knn(t, q, k, idx.data(), d.data());
    ASSERT_EQ(got, expect.size());
    for (size_t j = 0; j < got; ++j) {
      ASSERT_EQ(idx[j], expect[j].second) << "query " << s << " rank " << j;
      ASSERT_EQ(d[j], expect[j].first) << "query " << s << " rank " << j;
    }
    ASSERT_EQ(idx[got], -7) << "wrote past the answer";
  }
  dacpo_kdtree_free(t);
}

} // namespace

TEST(DacpoKdtree, RandomPointsMatchBruteForce)
{
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> xyz(3 * 5000);
  for (double& v : xyz)
    v = u(rng);
  expectMatchesBruteForce(xyz, 1, 7, 11);
  expectMatchesBruteForce(xyz, 16, 7, 12);
  expectMatchesBruteForce(xyz, 50, 31, 13);
}

TEST(DacpoKdtree, ClusteredPointsMatchBruteForce)
{
  // tight clusters of very different spread plus a thin plane: unbalanced boxes
  std::mt19937 rng(2);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> xyz;
  for (int c = 0; c < 8; ++c) {
    double cx = u(rng), cy = u(rng), cz = u(rng), s = std::pow(10.0, -1 - c % 4);
    for (int i = 0; i < 400; ++i) {
      xyz.push_back(cx + s * g(rng));
      xyz.push_back(cy + s * g(rng));
      xyz.push_back(cz + s * g(rng));
    }
  }
  for (int i = 0; i < 1000; ++i) { // the plane z = 0.5
    xyz.push_back(u(rng));
    xyz.push_back(u(rng));
    xyz.push_back(0.5);
  }
  expectMatchesBruteForce(xyz, 10, 3, 21);
}

TEST(DacpoKdtree, DuplicateHeavyPointsKeepTieOrder)
{
  // 40 sites with 50 copies each, on an integer grid: many exact ties in
  // distance, both from copies and from the grid's symmetry.
  std::vector<double> xyz;
  for (int c = 0; c < 50; ++c)
    for (int s = 0; s < 40; ++s) {
      xyz.push_back(s % 4);
      xyz.push_back((s / 4) % 5);
      xyz.push_back(s / 20);
    }
  expectMatchesBruteForce(xyz, 7, 5, 31);
  expectMatchesBruteForce(xyz, 120, 97, 32);
}

TEST(DacpoKdtree, AllIdenticalPointsBuildAndAnswerInIndexOrder)
{
  const size_t n = 200000; // would recurse n deep if splits were by value
  std::vector<double> xyz(3 * n, 0.25);
  dacpo_kdtree* t = build(xyz);
  ASSERT_NE(t, nullptr);
  double q[3] = {0.25, 0.25, 1.25};
  std::vector<int32_t> idx(5);
  std::vector<double> d(5);
  ASSERT_EQ(dacpo_kdtree_knn(t, q, 5, idx.data(), d.data()), 5u);
  for (int j = 0; j < 5; ++j) {
    EXPECT_EQ(idx[j], j);
    EXPECT_EQ(d[j], 1.0);
  }
  dacpo_kdtree_free(t);
}

TEST(DacpoKdtree, KLargerThanNReturnsAllPoints)
{
  std::vector<double> xyz = {0, 0, 0, 1, 0, 0, 0, 2, 0};
  dacpo_kdtree* t = build(xyz);
  double q[3] = {0.9, 0.0, 0.0};
  std::vector<int32_t> idx(10, -7);
  std::vector<double> d(10);
  ASSERT_EQ(dacpo_kdtree_knn(t, q, 10, idx.data(), d.data()), 3u);
  EXPECT_EQ(idx[0], 1);
  EXPECT_EQ(idx[1], 0);
  EXPECT_EQ(idx[2], 2);
  EXPECT_EQ(idx[3], -7);
  EXPECT_NEAR(d[1], 0.81, 1e-12);
  EXPECT_EQ(dacpo_kdtree_knn(t, q, 0, idx.data(), d.data()), 0u);
  dacpo_kdtree_free(t);
}

TEST(DacpoKdtree, EmptyAndSinglePointTrees)
{
  dacpo_kdtree* t = nullptr;
  dacpo_err err{};
  ASSERT_EQ(dacpo_kdtree_build(nullptr, 0, &t, &err), DACPO_OK);
  double q[3] = {1, 2, 3};
  int32_t idx[2] = {-7, -7};
  double d[2];
  EXPECT_EQ(dacpo_kdtree_knn(t, q, 2, idx, d), 0u);
  EXPECT_EQ(idx[0], -7);
  dacpo_kdtree_free(t);

  std::vector<double> one = {1, 2, 4};
  t = build(one);
  ASSERT_EQ(dacpo_kdtree_knn(t, q, 2, idx, d), 1u);
  EXPECT_EQ(idx[0], 0);
  EXPECT_EQ(d[0], 1.0);
  dacpo_kdtree_free(t);
  dacpo_kdtree_free(nullptr); // NULL-safe
}

TEST(DacpoKdtree, RejectsNullArguments)
{
  dacpo_err err{};
  EXPECT_EQ(dacpo_kdtree_build(nullptr, 3, nullptr, &err), DACPO_ERR_INVALID_ARGUMENT);
  dacpo_kdtree* t = nullptr;
  EXPECT_EQ(dacpo_kdtree_build(nullptr, 3, &t, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(t, nullptr);
}

TEST(DacpoKdtree, NonFiniteValuesAreRejected)
{
  std::vector<double> xyz = {0, 0, 0, 1, 0, 0, 0, NAN, 0};
  dacpo_kdtree* t = nullptr;
  dacpo_err err{};
  EXPECT_EQ(dacpo_kdtree_build(xyz.data(), 3, &t, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_STREQ(err.msg, "kdtree: point 2 has a non-finite coordinate");
  xyz[7] = 0.5;
  t = build(xyz);
  double q[3] = {0.0, INFINITY, 0.0};
  int32_t idx[2];
  double d[2];
  EXPECT_EQ(dacpo_kdtree_knn(t, q, 2, idx, d), 0u); // no answer rather than garbage
  dacpo_kdtree_free(t);
}

TEST(DacpoKdtree, ConcurrentQueriesAgree)
{
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const size_t n = 20000, k = 8;
  std::vector<double> xyz(3 * n);
  for (double& v : xyz)
    v = u(rng);
  dacpo_kdtree* t = build(xyz);
  std::vector<int32_t> a(n * k), b(n * k);
  auto run = [&](std::vector<int32_t>* out, size_t begin, size_t end) {
    std::vector<double> d(k);
    for (size_t i = begin; i < end; ++i)
      dacpo_kdtree_knn(t, &xyz[3 * i], k, &(*out)[i * k], d.data());
  };
  run(&a, 0, n);
  std::thread t1(run, &b, 0, n / 2), t2(run, &b, n / 2, n);
  t1.join();
  t2.join();
  EXPECT_EQ(a, b);
  dacpo_kdtree_free(t);
}

// The area one sample covers, on a square grid of spacing h: the 9 nearest of
// an interior point are itself, 4 at h and 4 at h sqrt(2), so the area is
// pi (2 h^2) / 8 = pi h^2 / 4. With 2 points: pi d^2 / 1; one point: 0.
TEST(DacpoKdtree, SampleAreaOnAGridIsPiSpacingSquaredOverFour)
{
  const double h = 0.03;
  std::vector<double> xyz;
  for (int i = 0; i < 11; ++i)
    for (int j = 0; j < 11; ++j) {
      xyz.push_back(i * h);
      xyz.push_back(j * h);
      xyz.push_back(0.5);
    }
  dacpo_kdtree* tree = nullptr;
  dacpo_err err{};
  ASSERT_EQ(dacpo_kdtree_build(xyz.data(), xyz.size() / 3, &tree, &err), DACPO_OK);
  const double* centre = xyz.data() + 3 * (5 * 11 + 5);
  EXPECT_NEAR(dacpo_kdtree_sample_area(tree, centre), M_PI * h * h / 4.0, 1e-15);
  dacpo_kdtree_free(tree);

  const double two[6] = {0, 0, 0, 0.2, 0, 0};
  ASSERT_EQ(dacpo_kdtree_build(two, 2, &tree, &err), DACPO_OK);
  EXPECT_NEAR(dacpo_kdtree_sample_area(tree, two), M_PI * 0.04, 1e-15);
  dacpo_kdtree_free(tree);

  ASSERT_EQ(dacpo_kdtree_build(two, 1, &tree, &err), DACPO_OK);
  EXPECT_EQ(dacpo_kdtree_sample_area(tree, two), 0.0);
  dacpo_kdtree_free(tree);
}

// The lower levels are built as tasks: the tree (its point order, hence its
// answers) is the same on 1, 2 or 3 threads, and matches the brute force.
// 60,000 points reach the task depth (32 subtrees); 20,000 of them coincide
// in pairs, and a flat slab makes one axis degenerate.
TEST(DacpoKdtree, TheTreeDoesNotDependOnTheThreads)
{
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> xyz;
  for (int i = 0; i < 40000; ++i)
    xyz.insert(xyz.end(), {u(rng), u(rng), 0.001 * u(rng)});
  for (int i = 0; i < 10000; ++i)
    for (int rep = 0; rep < 2; ++rep)
      xyz.insert(xyz.end(), {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]});
  const size_t n = xyz.size() / 3;
  std::vector<int32_t> order1;
  for (unsigned threads : {1u, 2u, 3u}) {
    dacpo_kdtree* t = nullptr;
    dacpo_err err{};
    ASSERT_EQ(dacpo_kdtree_build_threads(xyz.data(), n, threads, &t, &err), DACPO_OK)
        << err.msg;
    std::vector<int32_t> order(n);
    for (size_t pos = 0; pos < n; ++pos)
      order[pos] = dacpo_kdtree_order_at(t, pos);
    if (threads == 1)
      order1 = order;
    else
      EXPECT_EQ(order, order1) << threads << " threads";
    std::vector<int32_t> idx(12);
    std::vector<double> d(12);
    for (size_t s = 0; s < n; s += 997) {
      const double* q = xyz.data() + 3 * s;
      auto expect = bruteForce(xyz, q, 12);
      ASSERT_EQ(dacpo_kdtree_knn(t, q, 12, idx.data(), d.data()), 12u);
      for (size_t j = 0; j < 12; ++j) {
        ASSERT_EQ(idx[j], expect[j].second) << "query " << s << " rank " << j;
        ASSERT_EQ(d[j], expect[j].first);
      }
    }
    dacpo_kdtree_free(t);
  }
  std::vector<int32_t> sorted = order1;
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 0; i < n; ++i)
    ASSERT_EQ(sorted[i], static_cast<int32_t>(i)); // every point once
}
