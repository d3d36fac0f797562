// SPDX-License-Identifier: BSD-3-Clause
// The k-NN graph from the built-in kd-tree and from a caller's search (through
// dacpo_search, answering in input indices), its symmetric adjacency, and
// connected components.
extern "C" {
#include "dacpo_knn.h"
}

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace {

// Brute-force search over the caller's float array, in input indices, self
// included, nearest first; optional failure modes for the error tests.
struct BruteSearch {
  const float* xyz = nullptr;
  size_t n = 0;
  std::atomic<size_t> calls{0};
  size_t fail_at = SIZE_MAX;      // return non-zero for this query
  size_t bad_index_at = SIZE_MAX; // write an out-of-range index for this query
  int32_t bad_index = 0;
  bool overfill = false; // report more results than asked
  size_t cap = SIZE_MAX; // never return more than this many
};

int
bruteKnn(void* user, size_t query, size_t k, int32_t* idx, float* sqd, size_t* found)
{
  auto* s = static_cast<BruteSearch*>(user);
  s->calls++;
  if (query == s->fail_at)
    return 3;
  std::vector<std::pair<float, int32_t>> all(s->n);
  const float* q = s->xyz + 3 * query;
  for (size_t i = 0; i < s->n; ++i) {
    float dx = q[0] - s->xyz[3 * i], dy = q[1] - s->xyz[3 * i + 1],
          dz = q[2] - s->xyz[3 * i + 2];
    all[i] = {dx * dx + dy * dy + dz * dz, static_cast<int32_t>(i)};
  }
  size_t m = std::min({k, s->n, s->cap});
  std::partial_sort(all.begin(), all.begin() + m, all.end());
  for (size_t j = 0; j < m; ++j) {
    idx[j] = all[j].second;
    sqd[j] = all[j].first;
  }
  if (query == s->bad_index_at)
    idx[m / 2] = s->bad_index;
  *found = s->overfill ? k + 1 : m;
  return 0;
}

std::vector<float>
randomCloud(size_t n, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> xyz(3 * n);
  for (float& v : xyz)
    v = u(rng);
  return xyz;
}

struct Cloud {
  dacpo_cloud c{};
  explicit Cloud(const std::vector<float>& xyz)
  {
    dacpo_err err{};
    EXPECT_EQ(dacpo_cloud_build(xyz.data(), nullptr, xyz.size() / 3, &c, &err),
              DACPO_OK);
  }
  ~Cloud() { dacpo_cloud_free(&c); }
};

struct Graph {
  dacpo_knn_graph g{};
  ~Graph() { dacpo_knn_graph_free(&g); }
};

// Exact k nearest distinct neighbours by brute force in double, ties to lower index.
void
expectExactGraph(const dacpo_cloud& c, const dacpo_knn_graph& g)
{
  ASSERT_EQ(g.n, c.n);
  for (size_t i = 0; i < c.n; ++i) {
    std::vector<std::pair<double, int32_t>> all;
    for (size_t j = 0; j < c.n; ++j) {
      if (j == i)
        continue;
      double dx = c.xyz[3 * i] - c.xyz[3 * j], dy = c.xyz[3 * i + 1] - c.xyz[3 * j + 1],
             dz = c.xyz[3 * i + 2] - c.xyz[3 * j + 2];
      all.push_back({dx * dx + dy * dy + dz * dz, static_cast<int32_t>(j)});
    }
    std::sort(all.begin(), all.end());
    for (size_t r = 0; r < g.k; ++r) {
      ASSERT_EQ(g.idx[i * g.k + r], all[r].second) << "point " << i << " rank " << r;
      ASSERT_EQ(g.sqd[i * g.k + r], static_cast<float>(all[r].first));
    }
  }
}

} // namespace

TEST(DacpoKnn, BuiltinGraphIsExact)
{
  auto xyz = randomCloud(1500, 1);
  Cloud cl(xyz);
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&cl.c, 10, nullptr, 2, nullptr, &g.g, &err), DACPO_OK)
      << err.msg;
  EXPECT_EQ(g.g.k, 10u);
  expectExactGraph(cl.c, g.g);
}

TEST(DacpoKnn, CallbackMatchesBuiltin)
{
  auto xyz = randomCloud(9000, 2); // three chunks of points
  Cloud cl(xyz);
  BruteSearch bs;
  bs.xyz = xyz.data();
  bs.n = 9000;
  dacpo_search search{bruteKnn, &bs};
  Graph a, b, c1;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&cl.c, 8, nullptr, 1, nullptr, &a.g, &err), DACPO_OK);
  ASSERT_EQ(dacpo_knn_build(&cl.c, 8, &search, 2, nullptr, &b.g, &err), DACPO_OK)
      << err.msg;
  EXPECT_EQ(bs.calls.load(), 9000u); // no duplicates: one call per point
  ASSERT_EQ(dacpo_knn_build(&cl.c, 8, nullptr, 2, nullptr, &c1.g, &err), DACPO_OK);
  EXPECT_EQ(std::vector<int32_t>(a.g.idx, a.g.idx + 9000 * 8),
            std::vector<int32_t>(b.g.idx, b.g.idx + 9000 * 8));
  EXPECT_EQ(std::vector<float>(a.g.sqd, a.g.sqd + 9000 * 8),
            std::vector<float>(b.g.sqd, b.g.sqd + 9000 * 8));
  EXPECT_EQ(
      std::vector<int32_t>(a.g.idx, a.g.idx + 9000 * 8),
      std::vector<int32_t>(c1.g.idx, c1.g.idx + 9000 * 8)); // threads do not matter
}

TEST(DacpoKnn, CallbackOverDuplicatesAsksAgainAndMapsToDistinctPoints)
{
  // 300 sites; site s appears 1 + (s % 7) * 5 times (up to 31 copies), shuffled.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> xyz;
  for (int s = 0; s < 300; ++s) {
    float p[3] = {u(rng), u(rng), u(rng)};
    for (int c = 0; c < 1 + (s % 7) * 5; ++c)
      xyz.insert(xyz.end(), p, p + 3);
  }
  size_t n = xyz.size() / 3;
  std::vector<size_t> perm(n);
  for (size_t i = 0; i < n; ++i)
    perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  std::vector<float> shuffled(3 * n);
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      shuffled[3 * i + d] = xyz[3 * perm[i] + d];

  Cloud cl(shuffled);
  ASSERT_EQ(cl.c.n, 300u);
  BruteSearch bs;
  bs.xyz = shuffled.data();
  bs.n = n;
  dacpo_search search{bruteKnn, &bs};
  Graph builtin, cb;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&cl.c, 6, nullptr, 1, nullptr, &builtin.g, &err), DACPO_OK);
  ASSERT_EQ(dacpo_knn_build(&cl.c, 6, &search, 2, nullptr, &cb.g, &err), DACPO_OK)
      << err.msg;
  EXPECT_GT(bs.calls.load(), 300u); // heavy duplicates needed larger requests
  expectExactGraph(cl.c, cb.g);
  EXPECT_EQ(std::vector<int32_t>(builtin.g.idx, builtin.g.idx + 300 * 6),
            std::vector<int32_t>(cb.g.idx, cb.g.idx + 300 * 6));
}

TEST(DacpoKnn, ShortCallbackAnswersArePadded)
{
  auto xyz = randomCloud(100, 4);
  Cloud cl(xyz);
  BruteSearch bs;
  bs.xyz = xyz.data();
  bs.n = 100;
  bs.cap = 3; // self + at most 2 others
  dacpo_search search{bruteKnn, &bs};
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&cl.c, 5, &search, 1, nullptr, &g.g, &err), DACPO_OK);
  for (size_t i = 0; i < 100; ++i) {
    EXPECT_GE(g.g.idx[i * 5 + 1], 0);
    for (size_t r = 2; r < 5; ++r) {
      EXPECT_EQ(g.g.idx[i * 5 + r], -1);
      EXPECT_TRUE(std::isinf(g.g.sqd[i * 5 + r]));
    }
  }
}

TEST(DacpoKnn, FailingCallbackReportsNeighborSearch)
{
  auto xyz = randomCloud(10000, 5);
  Cloud cl(xyz);
  BruteSearch bs;
  bs.xyz = xyz.data();
  bs.n = 10000;
  bs.fail_at = 5000;
  dacpo_search search{bruteKnn, &bs};
  Graph g;
  dacpo_err err{};
  // Point 5000 lies in the second chunk of 4096 points; the first chunk succeeds.
  EXPECT_EQ(dacpo_knn_build(&cl.c, 4, &search, 2, nullptr, &g.g, &err),
            DACPO_ERR_NEIGHBOR_SEARCH);
  EXPECT_EQ(err.code, DACPO_ERR_NEIGHBOR_SEARCH);
  EXPECT_NE(std::string(err.msg).find("point 5000"), std::string::npos) << err.msg;
  EXPECT_EQ(g.g.idx, nullptr); // nothing left allocated
}

TEST(DacpoKnn, OutOfRangeCallbackIndexReportsNeighborSearch)
{
  auto xyz = randomCloud(200, 6);
  Cloud cl(xyz);
  for (int32_t bad : {200, -1, INT32_MAX}) {
    BruteSearch bs;
    bs.xyz = xyz.data();
    bs.n = 200;
    bs.bad_index_at = 17;
    bs.bad_index = bad;
    dacpo_search search{bruteKnn, &bs};
    Graph g;
    dacpo_err err{};
    EXPECT_EQ(dacpo_knn_build(&cl.c, 4, &search, 1, nullptr, &g.g, &err),
              DACPO_ERR_NEIGHBOR_SEARCH);
    EXPECT_NE(
        std::string(err.msg).find("index " + std::to_string(bad) + " for point 17"),
        std::string::npos)
        << err.msg;
  }
  BruteSearch over;
  over.xyz = xyz.data();
  over.n = 200;
  over.overfill = true;
  dacpo_search search{bruteKnn, &over};
  Graph g;
  dacpo_err err{};
  EXPECT_EQ(dacpo_knn_build(&cl.c, 4, &search, 1, nullptr, &g.g, &err),
            DACPO_ERR_NEIGHBOR_SEARCH);
}

TEST(DacpoKnn, RejectsKNotBelowDistinctCount)
{
  const std::vector<float> xyz = {0, 0, 0, 1, 0, 0, 0, 0, 0, 2, 0, 0};
  Cloud cl(xyz); // 3 distinct points
  Graph g;
  dacpo_err err{};
  EXPECT_EQ(dacpo_knn_build(&cl.c, 3, nullptr, 1, nullptr, &g.g, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  ASSERT_EQ(dacpo_knn_build(&cl.c, 2, nullptr, 1, nullptr, &g.g, &err), DACPO_OK);
  EXPECT_EQ(g.g.idx[0], 1); // point 0's neighbours: (1,0,0) then (2,0,0)
  EXPECT_EQ(g.g.idx[1], 2);
  EXPECT_EQ(g.g.sqd[1], 4.0f);
}

TEST(DacpoKnn, ProgressCanCancel)
{
  auto xyz = randomCloud(20000, 7);
  Cloud cl(xyz);
  Graph g;
  dacpo_err err{};
  std::vector<dacpo_stage> stages;
  dacpo_progress prog{[](void* user, dacpo_stage stage, double) {
                        static_cast<std::vector<dacpo_stage>*>(user)->push_back(stage);
                        return 1;
                      },
                      &stages};
  EXPECT_EQ(dacpo_knn_build(&cl.c, 4, nullptr, 1, &prog, &g.g, &err),
            DACPO_ERR_CANCELLED);
  ASSERT_FALSE(stages.empty());
  EXPECT_EQ(stages[0], DACPO_STAGE_NEIGHBORS);
  EXPECT_EQ(g.g.idx, nullptr);
}

TEST(DacpoKnn, AdjacencyIsTheSymmetrizedGraph)
{
  // 10,000 points: three chunks of rows, so 2 and 3 threads sort rows apart
  const size_t n = 10000;
  auto xyz = randomCloud(n, 8);
  Cloud cl(xyz);
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&cl.c, 10, nullptr, 2, nullptr, &g.g, &err), DACPO_OK);
  for (size_t k_use : {size_t(10), size_t(4)}) {
    std::vector<std::set<int32_t>> ref(n);
    for (size_t i = 0; i < n; ++i)
      for (size_t r = 0; r < k_use; ++r) {
        int32_t j = g.g.idx[i * 10 + r];
        ref[i].insert(j);
        ref[j].insert(static_cast<int32_t>(i));
      }
    for (unsigned threads : {1u, 2u, 3u}) {
      dacpo_adjacency a{};
      ASSERT_EQ(dacpo_adjacency_build_threads(&g.g, k_use, threads, &a, &err),
                DACPO_OK);
      ASSERT_EQ(a.n, n);
      EXPECT_EQ(a.start[0], 0u);
      size_t asym = 0;
      for (size_t i = 0; i < n; ++i) {
        std::vector<int32_t> row(a.nbr + a.start[i], a.nbr + a.start[i + 1]);
        ASSERT_EQ(row, std::vector<int32_t>(ref[i].begin(), ref[i].end()))
            << "row " << i << ", " << threads << " threads";
        for (int32_t j : row) {
          EXPECT_NE(j, static_cast<int32_t>(i));
          EXPECT_TRUE(std::binary_search(
              a.nbr + a.start[j], a.nbr + a.start[j + 1], static_cast<int32_t>(i)));
        }
        asym += row.size() > k_use;
      }
      EXPECT_GT(asym, 0u); // symmetrization added edges somewhere
      dacpo_adjacency_free(&a);
      EXPECT_EQ(a.start, nullptr);
    }
  }
}

TEST(DacpoKnn, TwoFarClustersAreTwoComponents)
{
  // Input alternates between two clusters 100 apart, and starts with a point of
  // cluster B, so component 0 must be B.
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> xyz;
  std::vector<int> cluster;
  for (int i = 0; i < 2000; ++i) {
    int c = (i % 3 == 0) ? 1 : 0;
    xyz.push_back(u(rng) + 100.0f * c);
    xyz.push_back(u(rng));
    xyz.push_back(u(rng));
    cluster.push_back(c);
  }
  Cloud cl(xyz);
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&cl.c, 8, nullptr, 2, nullptr, &g.g, &err), DACPO_OK);
  dacpo_adjacency a{};
  ASSERT_EQ(dacpo_adjacency_build(&g.g, 8, &a, &err), DACPO_OK);
  std::vector<int32_t> label(cl.c.n, -5);
  size_t nc = 0;
  ASSERT_EQ(dacpo_components_label(&a, label.data(), &nc, &err), DACPO_OK);
  EXPECT_EQ(nc, 2u);
  for (size_t i = 0; i < cl.c.n; ++i)
    EXPECT_EQ(label[i], cluster[cl.c.rep_input[i]] == 1 ? 0 : 1) << "point " << i;
  dacpo_adjacency_free(&a);
}

TEST(DacpoKnn, ComponentsOfIsolatedPointsAndEmptyGraph)
{
  dacpo_knn_graph g{};
  g.n = 4;
  g.k = 1;
  int32_t idx[4] = {1, -1, -1, -1}; // 0-1 linked, 2 and 3 alone
  float sqd[4] = {1, INFINITY, INFINITY, INFINITY};
  g.idx = idx;
  g.sqd = sqd;
  dacpo_adjacency a{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_adjacency_build(&g, 1, &a, &err), DACPO_OK);
  int32_t label[4];
  size_t nc = 0;
  ASSERT_EQ(dacpo_components_label(&a, label, &nc, &err), DACPO_OK);
  EXPECT_EQ(nc, 3u);
  EXPECT_EQ(label[0], 0);
  EXPECT_EQ(label[1], 0);
  EXPECT_EQ(label[2], 1);
  EXPECT_EQ(label[3], 2);
  dacpo_adjacency_free(&a);

  dacpo_adjacency empty{};
  ASSERT_EQ(dacpo_components_label(&empty, nullptr, &nc, &err), DACPO_OK);
  EXPECT_EQ(nc, 0u);
}

// After stage 1 only each row's reach is kept: its farthest finite squared
// distance (+inf when a row has none), one column, the indices freed.
TEST(DacpoKnn, KeepFarthestLeavesEachRowsReach)
{
  dacpo_knn_graph g{};
  g.n = 3;
  g.k = 3;
  g.idx = static_cast<int32_t*>(malloc(9 * sizeof(int32_t)));
  g.sqd = static_cast<float*>(malloc(9 * sizeof(float)));
  ASSERT_TRUE(g.idx && g.sqd);
  const float inf = INFINITY;
  const float rows[9] = {1.0f, 4.0f, 2.0f, 0.5f, 0.25f, inf, inf, inf, inf};
  for (int t = 0; t < 9; ++t) {
    g.sqd[t] = rows[t];
    g.idx[t] = t % 3;
  }
  dacpo_knn_graph_keep_farthest(&g);
  EXPECT_EQ(g.k, 1u);
  EXPECT_EQ(g.idx, nullptr);
  EXPECT_EQ(g.sqd[0], 4.0f);
  EXPECT_EQ(g.sqd[1], 0.5f);
  EXPECT_TRUE(std::isinf(g.sqd[2]));
  dacpo_knn_graph_keep_farthest(&g); // one column already: unchanged
  EXPECT_EQ(g.sqd[0], 4.0f);
  dacpo_knn_graph_free(&g);
}
