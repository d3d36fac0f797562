// SPDX-License-Identifier: BSD-3-Clause
// Input validation (status + message naming the first bad point) and exact
// duplicate merging (numbering, representatives, -0 == +0, normals).
extern "C" {
#include "dacpo_input.h"
}

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

std::vector<float>
gridCloud(size_t n)
{
  std::vector<float> xyz(3 * n);
  for (size_t i = 0; i < n; ++i) {
    xyz[3 * i] = static_cast<float>(i % 10);
    xyz[3 * i + 1] = static_cast<float>((i / 10) % 10);
    xyz[3 * i + 2] = static_cast<float>(i / 100);
  }
  return xyz;
}

std::vector<float>
upNormals(size_t n)
{
  std::vector<float> nrm(3 * n, 0.0f);
  for (size_t i = 0; i < n; ++i)
    nrm[3 * i + 2] = 1.0f;
  return nrm;
}

} // namespace

TEST(DacpoInput, AcceptsGoodInput)
{
  auto xyz = gridCloud(2000);
  auto nrm = upNormals(2000);
  dacpo_err err{};
  EXPECT_EQ(dacpo_input_check(xyz.data(), nullptr, 2000, &err), DACPO_OK);
  EXPECT_EQ(dacpo_input_check(xyz.data(), nrm.data(), 2000, &err), DACPO_OK);
}

TEST(DacpoInput, RejectsNullAndEmpty)
{
  float p[3] = {0, 0, 0};
  dacpo_err err{};
  EXPECT_EQ(dacpo_input_check(nullptr, nullptr, 5, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(err.code, DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_input_check(p, nullptr, 0, &err), DACPO_ERR_EMPTY_INPUT);
  EXPECT_EQ(dacpo_input_check(nullptr, nullptr, 0, &err), DACPO_ERR_EMPTY_INPUT);
  EXPECT_EQ(dacpo_input_check(p, nullptr, 1, nullptr), DACPO_OK); // err may be NULL
}

TEST(DacpoInput, RejectsCountBeyondInt32Indices)
{
  float p[3] = {0, 0, 0};
  dacpo_err err{};
  // The count is checked before any point is read.
  EXPECT_EQ(dacpo_input_check(p, nullptr, static_cast<size_t>(INT32_MAX), &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(err.msg).find("2147483647"), std::string::npos) << err.msg;
}

TEST(DacpoInput, NamesFirstNonFiniteCoordinate)
{
  auto xyz = gridCloud(3000);
  xyz[3 * 1042 + 1] = kNaN;
  xyz[3 * 2000] = kInf; // later: not reported
  dacpo_err err{};
  EXPECT_EQ(dacpo_input_check(xyz.data(), nullptr, 3000, &err),
            DACPO_ERR_NONFINITE_INPUT);
  EXPECT_STREQ(err.msg, "point 1042 has a non-finite coordinate (nan)");

  xyz[3 * 1042 + 1] = 0.0f;
  EXPECT_EQ(dacpo_input_check(xyz.data(), nullptr, 3000, &err),
            DACPO_ERR_NONFINITE_INPUT);
  EXPECT_STREQ(err.msg, "point 2000 has a non-finite coordinate (inf)");

  xyz[3 * 2000] = 0.0f;
  xyz[3 * 2999 + 2] = -kInf;
  EXPECT_EQ(dacpo_input_check(xyz.data(), nullptr, 3000, &err),
            DACPO_ERR_NONFINITE_INPUT);
  EXPECT_STREQ(err.msg, "point 2999 has a non-finite coordinate (-inf)");
}

TEST(DacpoInput, NamesFirstBadNormal)
{
  auto xyz = gridCloud(20);
  auto nrm = upNormals(20);
  dacpo_err err{};
  nrm[3 * 7 + 2] = 0.0f;
  nrm[3 * 9] = kNaN;
  EXPECT_EQ(dacpo_input_check(xyz.data(), nrm.data(), 20, &err),
            DACPO_ERR_NONFINITE_INPUT);
  EXPECT_STREQ(err.msg, "point 7 has a zero-length normal");

  nrm[3 * 7 + 2] = 1.0f;
  EXPECT_EQ(dacpo_input_check(xyz.data(), nrm.data(), 20, &err),
            DACPO_ERR_NONFINITE_INPUT);
  EXPECT_STREQ(err.msg, "point 9 has a non-finite normal (nan)");

  // 1e-21 in every component: length 1.7e-21 < 1e-20 counts as zero
  nrm[3 * 9] = 0.0f;
  nrm[3 * 4] = nrm[3 * 4 + 1] = nrm[3 * 4 + 2] = 1e-21f;
  EXPECT_EQ(dacpo_input_check(xyz.data(), nrm.data(), 20, &err),
            DACPO_ERR_NONFINITE_INPUT);
  EXPECT_STREQ(err.msg, "point 4 has a zero-length normal");

  // short but valid normals are accepted (they are normalized later)
  nrm[3 * 4] = nrm[3 * 4 + 1] = nrm[3 * 4 + 2] = 1e-10f;
  EXPECT_EQ(dacpo_input_check(xyz.data(), nrm.data(), 20, &err), DACPO_OK);
  // coordinates are checked before normals
  xyz[3 * 15] = kNaN;
  nrm[3 * 3 + 2] = 0.0f;
  EXPECT_EQ(dacpo_input_check(xyz.data(), nrm.data(), 20, &err),
            DACPO_ERR_NONFINITE_INPUT);
  EXPECT_STREQ(err.msg, "point 15 has a non-finite coordinate (nan)");
}

TEST(DacpoInput, MergesExactDuplicates)
{
  // 10 points, 3 of them copies: 1 == 0, 5 == 2, 9 == 2 -> 7 distinct
  const float xyz[30] = {1, 2, 3, 1, 2, 3, 4,  5, 6, 7, 8, 9,     1, 2, 3.5f,
                         4, 5, 6, 0, 0, 1, -1, 2, 3, 7, 8, 9.25f, 4, 5, 6};
  dacpo_cloud c{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_cloud_build(xyz, nullptr, 10, &c, &err), DACPO_OK) << err.msg;
  EXPECT_EQ(c.n, 7u);
  EXPECT_EQ(c.input_count, 10u);
  const int32_t map[10] = {0, 0, 1, 2, 3, 1, 4, 5, 6, 1};
  const int32_t rep[7] = {0, 2, 3, 4, 6, 7, 8};
  for (int i = 0; i < 10; ++i)
    EXPECT_EQ(c.input_to_point[i], map[i]) << "input " << i;
  for (int j = 0; j < 7; ++j) {
    EXPECT_EQ(c.rep_input[j], rep[j]) << "point " << j;
    for (int d = 0; d < 3; ++d)
      EXPECT_EQ(c.xyz[3 * j + d], static_cast<double>(xyz[3 * rep[j] + d]));
    for (int d = 0; d < 3; ++d)
      EXPECT_EQ(c.nrm[3 * j + d], 0.0); // no normals given
  }
  dacpo_cloud_free(&c);
  EXPECT_EQ(c.xyz, nullptr);
  EXPECT_EQ(c.n, 0u);
  dacpo_cloud_free(&c); // idempotent
  dacpo_cloud_free(nullptr);
}

TEST(DacpoInput, MergesNegativeAndPositiveZero)
{
  const float xyz[9] = {0.0f, -0.0f, 1.0f, -0.0f, 0.0f, 1.0f, 0.0f, 0.0f, -1.0f};
  dacpo_cloud c{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_cloud_build(xyz, nullptr, 3, &c, &err), DACPO_OK);
  EXPECT_EQ(c.n, 2u);
  EXPECT_EQ(c.input_to_point[0], 0);
  EXPECT_EQ(c.input_to_point[1], 0);
  EXPECT_EQ(c.input_to_point[2], 1);
  dacpo_cloud_free(&c);
}

TEST(DacpoInput, RepresentativeNormalIsNormalized)
{
  const float xyz[9] = {1, 1, 1, 2, 2, 2, 1, 1, 1};
  const float nrm[9] = {0, 3, 4, 2, 0, 0, 0, 0, -7}; // input 2's normal is dropped
  dacpo_cloud c{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_cloud_build(xyz, nrm, 3, &c, &err), DACPO_OK);
  ASSERT_EQ(c.n, 2u);
  EXPECT_DOUBLE_EQ(c.nrm[0], 0.0);
  EXPECT_DOUBLE_EQ(c.nrm[1], 0.6);
  EXPECT_DOUBLE_EQ(c.nrm[2], 0.8);
  EXPECT_DOUBLE_EQ(c.nrm[3], 1.0);
  EXPECT_DOUBLE_EQ(c.nrm[4], 0.0);
  dacpo_cloud_free(&c);
}

TEST(DacpoInput, BuildReportsBadInputAndLeavesCloudEmpty)
{
  auto xyz = gridCloud(50);
  xyz[3 * 33 + 2] = kNaN;
  dacpo_cloud c{};
  dacpo_err err{};
  EXPECT_EQ(dacpo_cloud_build(xyz.data(), nullptr, 50, &c, &err),
            DACPO_ERR_NONFINITE_INPUT);
  EXPECT_STREQ(err.msg, "point 33 has a non-finite coordinate (nan)");
  EXPECT_EQ(c.xyz, nullptr);
  EXPECT_EQ(c.input_to_point, nullptr);
  EXPECT_EQ(dacpo_cloud_build(xyz.data(), nullptr, 0, &c, &err), DACPO_ERR_EMPTY_INPUT);
  EXPECT_EQ(dacpo_cloud_build(xyz.data(), nullptr, 5, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
}

TEST(DacpoInput, ManyDuplicatesMatchReferenceMapping)
{
  // 30000 points drawn from 2000 sites with negative, positive and signed-zero
  // coordinates; the reference numbers sites by their first occurrence.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> site(0, 1999);
  std::uniform_real_distribution<float> u(-100.0f, 100.0f);
  std::vector<std::array<float, 3>> sites(2000);
  for (auto& s : sites)
    s = {u(rng), u(rng), u(rng)};
  sites[5] = {0.0f, 0.0f, 0.0f};
  sites[6] = {-0.0f, 0.0f, -0.0f}; // same point as site 5
  sites[7] = {sites[8][0], sites[8][1], std::nextafter(sites[8][2], 1000.0f)};
  const size_t n = 30000;
  std::vector<float> xyz(3 * n);
  for (size_t i = 0; i < n; ++i) {
    const auto& s = sites[site(rng)];
    for (int d = 0; d < 3; ++d)
      xyz[3 * i + d] = s[d];
  }
  std::map<std::array<float, 3>, int32_t> first; // -0 == +0 under operator<
  std::vector<int32_t> expect_map(n), expect_rep;
  for (size_t i = 0; i < n; ++i) {
    std::array<float, 3> key = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
    auto it = first.find(key);
    if (it == first.end()) {
      it = first.emplace(key, static_cast<int32_t>(expect_rep.size())).first;
      expect_rep.push_back(static_cast<int32_t>(i));
    }
    expect_map[i] = it->second;
  }
  dacpo_cloud c{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_cloud_build(xyz.data(), nullptr, n, &c, &err), DACPO_OK);
  ASSERT_EQ(c.n, expect_rep.size());
  EXPECT_LE(c.n, 1999u); // sites 5 and 6 merged
  EXPECT_EQ(std::vector<int32_t>(c.input_to_point, c.input_to_point + n), expect_map);
  EXPECT_EQ(std::vector<int32_t>(c.rep_input, c.rep_input + c.n), expect_rep);
  dacpo_cloud_free(&c);
}
