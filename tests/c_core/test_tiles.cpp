// SPDX-License-Identifier: BSD-3-Clause
// Tiles (dacpo_advanced.h): the plan's cells and halos on a line of points
// whose answer is known, the automatic halo on a grid of known spacing, the
// join on evidence with a known spanning tree, the errors, and a room oriented
// tile by tile whose tiles were turned over at random: the join must give the
// same normals as the untouched tiles.
#include "scene_fixture.hpp"

#include <dacpo/dacpo_advanced.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <utility>
#include <vector>

namespace {

using PlanPtr = std::unique_ptr<dacpo_tile_plan, decltype(&dacpo_tile_plan_free)>;

PlanPtr
makePlan(const std::vector<float>& sample,
         uint64_t total,
         uint64_t max_points,
         double halo,
         dacpo_status* st = nullptr)
{
  dacpo_tile_plan* p = nullptr;
  char msg[256] = "";
  const dacpo_status s =
      dacpo_tile_plan_create(sample.data(), sample.size() / 3, total, max_points, halo, &p, msg, sizeof(msg));
  if (st)
    *st = s;
  return PlanPtr(p, dacpo_tile_plan_free);
}

// Points x = 0, 1, ..., n-1 on a line, in shuffled order.
std::vector<float>
Line(int n)
{
  std::vector<int> x(n);
  for (int i = 0; i < n; ++i)
    x[i] = i;
  std::shuffle(x.begin(), x.end(), std::mt19937(3));
  std::vector<float> xyz;
  for (int v : x)
    xyz.insert(xyz.end(), {(float)v, 0.0f, 0.0f});
  return xyz;
}

TEST(DacpoTiles, LineCellsAndHalos)
{
  // 1,024 points, at most 0.8 x 200 = 160 own points per tile: cut at the
  // median three times, 8 tiles of 128 points, tile t = [128 t, 128 t + 128).
  const std::vector<float> xyz = Line(1024);
  auto plan = makePlan(xyz, 1024, 200, 10.0);
  ASSERT_TRUE(plan);
  ASSERT_EQ(dacpo_tile_plan_count(plan.get()), 8u);
  EXPECT_DOUBLE_EQ(dacpo_tile_plan_halo(plan.get()), 10.0);
  for (int x = 0; x < 1024; ++x) {
    const float p[3] = {(float)x, 0.0f, 0.0f};
    int32_t halo[8];
    size_t nh = 99;
    const int32_t own = dacpo_tile_locate(plan.get(), p, halo, 8, &nh);
    ASSERT_EQ(own, x / 128) << x;
    // the next cell starts at 128 (own + 1); it holds x in its halo when
    // 128 (own + 1) - x <= 10, the previous one when x - 128 own < 10
    std::vector<int32_t> want;
    if (own > 0 && x - 128 * own < 10)
      want.push_back(own - 1);
    if (own < 7 && 128 * (own + 1) - x <= 10)
      want.push_back(own + 1);
    ASSERT_EQ(nh, want.size()) << x;
    for (size_t t = 0; t < nh; ++t)
      EXPECT_EQ(halo[t], want[t]) << x;
  }
  // own 128 + halo 10 (ends) or 20 (inner tiles)
  EXPECT_EQ(dacpo_tile_plan_estimate(plan.get(), 0), 138u);
  EXPECT_EQ(dacpo_tile_plan_estimate(plan.get(), 3), 148u);
  // beyond the sample's extent: the outer cells are unbounded
  const float far[3] = {-1e6f, 5.0f, 5.0f};
  EXPECT_EQ(dacpo_tile_locate(plan.get(), far, nullptr, 0, nullptr), 0);
  const float nan[3] = {NAN, 0.0f, 0.0f};
  EXPECT_EQ(dacpo_tile_locate(plan.get(), nan, nullptr, 0, nullptr), -1);
  // a sample of every 4th point scales to the total: the same cells
  std::vector<float> every4;
  for (int x = 0; x < 1024; x += 4)
    every4.insert(every4.end(), {(float)x, 0.0f, 0.0f});
  auto plan4 = makePlan(every4, 1024, 200, 10.0);
  ASSERT_TRUE(plan4);
  EXPECT_EQ(dacpo_tile_plan_count(plan4.get()), 8u);
  // one tile when everything fits
  auto one = makePlan(xyz, 1024, 2000, 0.0);
  ASSERT_TRUE(one);
  EXPECT_EQ(dacpo_tile_plan_count(one.get()), 1u);
}

TEST(DacpoTiles, EqualCoordinatesNeverSplit)
{
  // 200 copies of 4 positions: cuts fall between equal values, every tile is
  // non-empty, and a cell of one repeated position is left whole.
  std::vector<float> xyz;
  for (int i = 0; i < 800; ++i)
    xyz.insert(xyz.end(), {(float)(i % 4), 0.0f, 0.0f});
  auto plan = makePlan(xyz, 800, 100, 0.5);
  ASSERT_TRUE(plan);
  EXPECT_EQ(dacpo_tile_plan_count(plan.get()), 4u);
  for (int v = 0; v < 4; ++v) {
    const float p[3] = {(float)v, 0.0f, 0.0f};
    EXPECT_EQ(dacpo_tile_locate(plan.get(), p, nullptr, 0, nullptr), v);
  }
}

TEST(DacpoTiles, AutomaticHaloFollowsTheSpacing)
{
  // A 100 x 100 grid of spacing 0.01 m sampled at every other row and column:
  // the sample's spacing is 0.02, the cloud's 0.02 x sqrt(2,500 / 10,000).
  std::vector<float> sample;
  for (int i = 0; i < 100; i += 2)
    for (int j = 0; j < 100; j += 2)
      sample.insert(sample.end(), {0.01f * i, 0.01f * j, 0.0f});
  auto plan = makePlan(sample, 10000, 3000, 0.0);
  ASSERT_TRUE(plan);
  EXPECT_NEAR(dacpo_tile_plan_halo(plan.get()), 16 * 0.01, 1e-4);
  EXPECT_EQ(dacpo_tile_plan_count(plan.get()), 8u); // 10,000 -> 1,250 per tile
  // every point twice (a scan concatenated with itself): the same spacing
  std::vector<float> twice = sample;
  twice.insert(twice.end(), sample.begin(), sample.end());
  auto dup = makePlan(twice, 20000, 10000, 0.0);
  ASSERT_TRUE(dup);
  EXPECT_NEAR(dacpo_tile_plan_halo(dup.get()), 16 * 0.01, 1e-4); // was 0
}

TEST(DacpoTiles, BadArgumentsAreRefused)
{
  const std::vector<float> xyz = Line(100);
  dacpo_status st = DACPO_OK;
  EXPECT_FALSE(makePlan({}, 100, 100, 0.0, &st));
  EXPECT_EQ(st, DACPO_ERR_EMPTY_INPUT);
  EXPECT_FALSE(makePlan(xyz, 50, 100, 0.0, &st)); // sample larger than total
  EXPECT_EQ(st, DACPO_ERR_EMPTY_INPUT);
  EXPECT_FALSE(makePlan(xyz, 100, 15, 0.0, &st));
  EXPECT_EQ(st, DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_FALSE(makePlan(xyz, 100, 100, -1.0, &st));
  EXPECT_EQ(st, DACPO_ERR_INVALID_ARGUMENT);
  std::vector<float> bad = xyz;
  bad[31] = INFINITY;
  EXPECT_FALSE(makePlan(bad, 100, 100, 0.0, &st));
  EXPECT_EQ(st, DACPO_ERR_NONFINITE_INPUT);
  // 100,000 sample points standing for 10^12: more than 65,536 tiles
  EXPECT_FALSE(makePlan(Line(100000), 1000000000000ull, 16, 1.0, &st));
  EXPECT_EQ(st, DACPO_ERR_INVALID_ARGUMENT);
  dacpo_tile_plan* p = nullptr;
  char msg[128] = "";
  EXPECT_EQ(dacpo_tile_plan_create(xyz.data(), 100, 100, 100, 0.0, nullptr, msg, sizeof(msg)),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_STRNE(msg, "");
  EXPECT_EQ(p, nullptr);

  uint8_t flip[2];
  const dacpo_tile_overlap out_of_range{0, 2, 1.0, 0.0};
  EXPECT_EQ(dacpo_tile_join(2, &out_of_range, 1, nullptr, flip, nullptr, 0),
            DACPO_ERR_INVALID_ARGUMENT);
  const dacpo_tile_overlap negative{0, 1, -1.0, 0.0};
  EXPECT_EQ(dacpo_tile_join(2, &negative, 1, nullptr, flip, nullptr, 0),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_tile_join(2, nullptr, 0, nullptr, nullptr, nullptr, 0),
            DACPO_ERR_INVALID_ARGUMENT);
}

TEST(DacpoTiles, JoinFollowsTheStrongestEvidence)
{
  // 0 -same- 1 -opposite- 2 -opposite- 3, and a weak 0 -opposite- 3 that the
  // spanning tree leaves out; tile 4 has no evidence. (0,1) is given from both
  // ends and summed: 5 same + 1 same vs 2 opposite.
  const std::vector<dacpo_tile_overlap> ov = {{0, 1, 5.0, 2.0},
                                              {1, 0, 1.0, 0.0},
                                              {2, 1, 0.5, 9.0},
                                              {2, 3, 0.0, 20.0},
                                              {3, 0, 0.1, 0.3}};
  uint8_t flip[5];
  ASSERT_EQ(dacpo_tile_join(5, ov.data(), ov.size(), nullptr, flip, nullptr, 0), DACPO_OK);
  EXPECT_EQ(std::vector<int>(flip, flip + 5), (std::vector<int>{0, 0, 1, 0, 0}));
  // when tile 2 holds most of the points, its own sign is kept
  const uint64_t points[5] = {10, 10, 1000, 10, 10};
  ASSERT_EQ(dacpo_tile_join(5, ov.data(), ov.size(), points, flip, nullptr, 0), DACPO_OK);
  EXPECT_EQ(std::vector<int>(flip, flip + 5), (std::vector<int>{1, 1, 0, 1, 0}));
}

using HaloNormals = std::vector<std::map<size_t, std::vector<float>>>;

// Each point's own tile into owner, and each tile's own and halo points into
// members (unsorted).
void
tileMembers(const dacpo_tile_plan* plan,
            const GeneratedScene& sc,
            std::vector<int32_t>& owner,
            std::vector<std::vector<size_t>>& members)
{
  const size_t n = sc.s.n;
  for (size_t i = 0; i < n; ++i) {
    int32_t halo[32];
    size_t nh = 0;
    owner[i] = dacpo_tile_locate(plan, sc.s.xyz + 3 * i, halo, 32, &nh);
    ASSERT_LE(nh, 32u);
    members[owner[i]].push_back(i);
    for (size_t h = 0; h < nh; ++h)
      members[halo[h]].push_back(i);
  }
}

// Orients each tile's members in input order, every odd tile's answer negated:
// own points into normal (counted in own_points), halo points into halo_normal.
void
orientTiles(dacpo_ctx* ctx,
            const dacpo_params& p,
            const GeneratedScene& sc,
            std::vector<std::vector<size_t>>& members,
            const std::vector<int32_t>& owner,
            std::vector<float>& normal,
            HaloNormals& halo_normal,
            std::vector<uint64_t>& own_points)
{
  const size_t T = members.size();
  for (size_t t = 0; t < T; ++t) {
    std::vector<size_t>& m = members[t];
    std::sort(m.begin(), m.end());
    std::vector<float> xyz, nrm(3 * m.size(), 0.0f);
    for (size_t i : m)
      xyz.insert(xyz.end(), sc.s.xyz + 3 * i, sc.s.xyz + 3 * i + 3);
    ASSERT_EQ(dacpo_orient(ctx, &p, nullptr, nullptr, xyz.data(), nrm.data(), m.size()), DACPO_OK)
        << dacpo_ctx_last_error(ctx);
    const float s = t % 2 ? -1.0f : 1.0f;
    for (size_t j = 0; j < m.size(); ++j) {
      float* d = owner[m[j]] == (int32_t)t ? &normal[3 * m[j]] : nullptr;
      std::vector<float> v = {s * nrm[3 * j], s * nrm[3 * j + 1], s * nrm[3 * j + 2]};
      if (d) {
        std::copy(v.begin(), v.end(), d);
        own_points[t]++;
      }
      else
        halo_normal[t][m[j]] = v;
    }
  }
}

// The join's evidence: for each tile and each tile owning one of its halo
// points, the agreement of the two answers there, summed.
std::vector<dacpo_tile_overlap>
overlapEvidence(size_t T,
                const std::vector<int32_t>& owner,
                const std::vector<float>& normal,
                const HaloNormals& halo_normal)
{
  std::map<std::pair<uint32_t, uint32_t>, dacpo_tile_overlap> ev;
  for (size_t t = 0; t < T; ++t)
    for (const auto& [i, v] : halo_normal[t]) {
      const uint32_t o = (uint32_t)owner[i];
      dacpo_tile_overlap& e = ev[{(uint32_t)t, o}];
      e.a = (uint32_t)t;
      e.b = o;
      const double d = v[0] * normal[3 * i] + v[1] * normal[3 * i + 1] + v[2] * normal[3 * i + 2];
      (d >= 0 ? e.same : e.opposite) += std::fabs(d);
    }
  std::vector<dacpo_tile_overlap> list;
  for (const auto& kv : ev)
    list.push_back(kv.second);
  return list;
}

// A room oriented tile by tile (own + halo points in input order, each by
// dacpo_orient), every other tile's answer negated before the join, as a tile
// with its own global sign may come out: the join must undo exactly those.
TEST(DacpoTiles, RoomTilesJoinToOneSign)
{
  GeneratedScene sc(DACPO_SCENE_ROOM, 40000, 5);
  ASSERT_TRUE(sc.ok);
  const size_t n = sc.s.n;
  std::vector<float> sample;
  for (size_t i = 0; i < n; i += 4)
    sample.insert(sample.end(), sc.s.xyz + 3 * i, sc.s.xyz + 3 * i + 3);
  auto plan = makePlan(sample, n, 14000, 0.0);
  ASSERT_TRUE(plan);
  const size_t T = dacpo_tile_plan_count(plan.get());
  ASSERT_GE(T, 4u);
  std::vector<std::vector<size_t>> members(T);
  std::vector<int32_t> owner(n);
  ASSERT_NO_FATAL_FAILURE(tileMembers(plan.get(), sc, owner, members));
  dacpo_params p;
  dacpo_params_init(&p);
  p.estimate_normals = 1;
  p.num_threads = 2;
  p.seed = 1;
  dacpo_ctx* ctx = nullptr;
  ASSERT_EQ(dacpo_ctx_create(&ctx), DACPO_OK);
  std::vector<float> normal(3 * n, 0.0f);
  std::vector<std::map<size_t, std::vector<float>>> halo_normal(T);
  std::vector<uint64_t> own_points(T, 0);
  ASSERT_NO_FATAL_FAILURE(
      orientTiles(ctx, p, sc, members, owner, normal, halo_normal, own_points));
  dacpo_ctx_free(ctx);
  const std::vector<dacpo_tile_overlap> list =
      overlapEvidence(T, owner, normal, halo_normal);
  std::vector<uint8_t> flip(T);
  ASSERT_EQ(dacpo_tile_join(T, list.data(), list.size(), own_points.data(), flip.data(), nullptr, 0),
            DACPO_OK);
  size_t odd_flipped = 0, even_flipped = 0;
  for (size_t t = 0; t < T; ++t)
    (t % 2 ? odd_flipped : even_flipped) += flip[t];
  // every odd tile flipped back, no even one (or the exact complement)
  EXPECT_TRUE((odd_flipped == T / 2 && even_flipped == 0) ||
              (odd_flipped == 0 && even_flipped == (T + 1) / 2))
      << odd_flipped << " " << even_flipped;
  for (size_t i = 0; i < n; ++i)
    if (flip[owner[i]])
      for (int k = 0; k < 3; ++k)
        normal[3 * i + k] = -normal[3 * i + k];
  const double tiled = dacpo_score_oriented(sc.s.normals, normal.data(), n, nullptr, nullptr);
  std::vector<float> whole(3 * n, 0.0f);
  dacpo_ctx* c2 = nullptr;
  ASSERT_EQ(dacpo_ctx_create(&c2), DACPO_OK);
  ASSERT_EQ(dacpo_orient(c2, &p, nullptr, nullptr, sc.s.xyz, whole.data(), n), DACPO_OK);
  dacpo_ctx_free(c2);
  const double in_core = dacpo_score_oriented(sc.s.normals, whole.data(), n, nullptr, nullptr);
  std::printf("room 40K, %zu tiles, halo %.3f m: tiled %.2f %% wrong, in one piece %.2f %%\n",
              T,
              dacpo_tile_plan_halo(plan.get()),
              tiled,
              in_core);
  EXPECT_LT(tiled, in_core + 2.0);
}

} // namespace
