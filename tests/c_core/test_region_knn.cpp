// SPDX-License-Identifier: BSD-3-Clause
// dacpo_region_knn (dacpo_advanced.h): rows of a region searched among its own
// points and a halo equal the whole cloud's k nearest (brute force, ties to the
// lower number) wherever they are reported complete, on a cloud with exact
// duplicates and grid ties; too thin a halo is reported, not guessed.
#include <dacpo/dacpo_advanced.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace {

constexpr double kInf = HUGE_VAL;

// 1,500 random points in a 2 x 1 x 0.2 box, a 10 x 10 grid (equal distances),
// and 40 exact duplicates of earlier points, in shuffled global order.
std::vector<float>
Cloud()
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> xyz;
  for (int i = 0; i < 1500; ++i)
    xyz.insert(xyz.end(), {2 * u(rng), u(rng), 0.2f * u(rng)});
  for (int i = 0; i < 100; ++i)
    xyz.insert(xyz.end(), {0.9f + 0.02f * (i % 10), 0.4f + 0.02f * (i / 10), 0.5f});
  for (int i = 0; i < 40; ++i) {
    const size_t j = 37 * i;
    xyz.insert(xyz.end(), {xyz[3 * j], xyz[3 * j + 1], xyz[3 * j + 2]});
  }
  return xyz;
}

// The k nearest of point q by (squared distance in double, index).
std::vector<int32_t>
BruteForce(const std::vector<float>& xyz, size_t q, size_t k)
{
  const size_t n = xyz.size() / 3;
  std::vector<std::pair<double, int32_t>> d(n);
  for (size_t j = 0; j < n; ++j) {
    double s = 0;
    for (int a = 0; a < 3; ++a) {
      const double e = double(xyz[3 * j + a]) - double(xyz[3 * q + a]);
      s += e * e;
    }
    d[j] = {s, int32_t(j)};
  }
  std::partial_sort(d.begin(), d.begin() + k, d.end());
  std::vector<int32_t> r(k);
  for (size_t t = 0; t < k; ++t)
    r[t] = d[t].second;
  return r;
}

} // namespace

TEST(DacpoRegionKnn, SlabRowsEqualTheWholeCloudWhereComplete)
{
  const std::vector<float> xyz = Cloud();
  const size_t n = xyz.size() / 3, k = 15;
  for (double halo : {0.02, 0.08, 0.5}) {
    size_t complete_rows = 0, rows = 0;
    const double cuts[4] = {-kInf, 0.7, 1.3, kInf};
    for (int s = 0; s < 3; ++s) {
      // the slab's own points and its halo, in global order
      const double lo = cuts[s], hi = cuts[s + 1];
      std::vector<float> r;
      std::vector<uint8_t> own;
      std::vector<size_t> global;
      for (size_t i = 0; i < n; ++i) {
        const double x = xyz[3 * i];
        if (x >= lo - halo && x < hi + halo) {
          r.insert(r.end(), {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]});
          own.push_back(x >= lo && x < hi);
          global.push_back(i);
        }
      }
      const size_t m = std::count(own.begin(), own.end(), 1);
      std::vector<int32_t> nbr(m * k);
      std::vector<float> sqd(m * k);
      std::vector<uint8_t> complete(m);
      const double box_lo[3] = {lo - halo, -kInf, -kInf};
      const double box_hi[3] = {hi + halo, kInf, kInf};
      char msg[256];
      ASSERT_EQ(dacpo_region_knn(r.data(),
                                 own.data(),
                                 own.size(),
                                 k,
                                 box_lo,
                                 box_hi,
                                 nbr.data(),
                                 sqd.data(),
                                 complete.data(),
                                 msg,
                                 sizeof(msg)),
                DACPO_OK)
          << msg;
      size_t j = 0;
      for (size_t i = 0; i < own.size(); ++i) {
        if (!own[i])
          continue;
        ++rows;
        if (complete[j]) {
          ++complete_rows;
          const std::vector<int32_t> want = BruteForce(xyz, global[i], k);
          for (size_t t = 0; t < k; ++t)
            ASSERT_EQ(global[size_t(nbr[j * k + t])], size_t(want[t]))
                << "halo " << halo << " point " << global[i] << " rank " << t;
          // the point itself (or an earlier exact duplicate) first
          EXPECT_EQ(sqd[j * k], 0.0f);
          EXPECT_LE(nbr[j * k], int32_t(i));
        }
        ++j;
      }
    }
    EXPECT_EQ(rows, n);
    if (halo == 0.02)
      EXPECT_LT(complete_rows, n) << "a thin halo leaves rows near the cuts open";
    if (halo == 0.5)
      EXPECT_EQ(complete_rows, n) << "a wide halo covers every ball";
  }
}

TEST(DacpoRegionKnn, FewerPointsThanKAndBadInput)
{
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 2, 0};
  const uint8_t own[3] = {1, 0, 1};
  int32_t nbr[8];
  float sqd[8];
  uint8_t complete[2];
  const double open_lo[3] = {-kInf, -kInf, -kInf}, open_hi[3] = {kInf, kInf, kInf};
  char msg[256];
  // k = 4 among 3 points: padded; complete only when the box is all of space
  ASSERT_EQ(
      dacpo_region_knn(xyz, own, 3, 4, open_lo, open_hi, nbr, sqd, complete, msg, 256),
      DACPO_OK);
  EXPECT_EQ(nbr[0], 0);
  EXPECT_EQ(nbr[1], 1);
  EXPECT_EQ(nbr[2], 2);
  EXPECT_EQ(nbr[3], -1);
  EXPECT_TRUE(std::isinf(sqd[3]));
  EXPECT_EQ(nbr[4], 2);
  EXPECT_FLOAT_EQ(sqd[5], 4.0f); // point 0 is 2 away from point 2
  EXPECT_EQ(complete[0], 1);
  const double lo[3] = {-5, -5, -5}, hi[3] = {5, 5, 5};
  ASSERT_EQ(dacpo_region_knn(xyz, own, 3, 4, lo, hi, nbr, sqd, complete, msg, 256),
            DACPO_OK);
  EXPECT_EQ(complete[0], 0);
  ASSERT_EQ(dacpo_region_knn(xyz, own, 3, 2, lo, hi, nbr, sqd, complete, msg, 256),
            DACPO_OK);
  EXPECT_EQ(complete[0], 1);
  // without distances: the same rows and flags
  int32_t rows[4];
  uint8_t flags[2];
  ASSERT_EQ(dacpo_region_knn(xyz, own, 3, 2, lo, hi, rows, nullptr, flags, msg, 256),
            DACPO_OK);
  for (int t = 0; t < 4; ++t)
    EXPECT_EQ(rows[t], nbr[t]) << t;
  EXPECT_EQ(flags[0], complete[0]);
  EXPECT_EQ(flags[1], complete[1]);

  EXPECT_EQ(dacpo_region_knn(xyz, own, 3, 0, lo, hi, nbr, sqd, complete, msg, 256),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_region_knn(nullptr, own, 3, 2, lo, hi, nbr, sqd, complete, msg, 256),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("NULL"), std::string::npos) << msg;
  const float bad[9] = {0, 0, 0, NAN, 0, 0, 0, 2, 0};
  EXPECT_EQ(dacpo_region_knn(bad, own, 3, 2, lo, hi, nbr, sqd, complete, msg, 256),
            DACPO_ERR_NONFINITE_INPUT);
  EXPECT_NE(std::string(msg).find("point 1"), std::string::npos) << msg;
}
