// SPDX-License-Identifier: BSD-3-Clause
// Tests for stage 1, block segmentation (c_core/src/dacpo_segment.c).
// Clouds and adjacencies are built by hand here (grids with 4-neighbour edges,
// brute-force symmetric k-NN), so the tests do not depend on dacpo_knn.c.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <deque>
#include <random>
#include <set>
#include <vector>

extern "C" {
#include "dacpo_segment.h"
}

namespace {

// A cloud plus adjacency whose arrays are owned by vectors.
struct Scene {
  std::vector<double> xyz;
  std::vector<double> nrm;
  std::vector<int32_t> ident;
  std::vector<size_t> start;
  std::vector<int32_t> nbr;
  std::vector<int32_t> component;
  size_t num_components = 1;
  dacpo_cloud cloud{};
  dacpo_adjacency adj{};

  size_t
  n() const
  {
    return xyz.size() / 3;
  }

  // Call after xyz/start/nbr are final.
  void
  finish()
  {
    size_t count = n();
    nrm.assign(3 * count, 0.0);
    ident.resize(count);
    for (size_t i = 0; i < count; ++i)
      ident[i] = (int32_t)i;
    if (component.empty())
      component.assign(count, 0);
    cloud.n = count;
    cloud.input_count = count;
    cloud.xyz = xyz.data();
    cloud.nrm = nrm.data();
    cloud.rep_input = ident.data();
    cloud.input_to_point = ident.data();
    adj.n = count;
    adj.start = start.data();
    adj.nbr = nbr.data();
  }
};

// Appends a w x h grid (spacing 1, offset ox) with 4-neighbour edges, as
// component comp, into the point lists rows (adjacency rows, rebuilt later).
void
add_grid(std::vector<double>& xyz,
         std::vector<std::vector<int32_t>>& rows,
         std::vector<int32_t>& component,
         int w,
         int h,
         double ox,
         int32_t comp)
{
  int32_t base = (int32_t)(xyz.size() / 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      xyz.push_back(ox + x);
      xyz.push_back(y);
      xyz.push_back(0.0);
      std::vector<int32_t> r;
      if (y > 0)
        r.push_back(base + (y - 1) * w + x);
      if (x > 0)
        r.push_back(base + y * w + x - 1);
      if (x + 1 < w)
        r.push_back(base + y * w + x + 1);
      if (y + 1 < h)
        r.push_back(base + (y + 1) * w + x);
      std::sort(r.begin(), r.end());
      rows.push_back(r);
      component.push_back(comp);
    }
}

void
rows_to_csr(const std::vector<std::vector<int32_t>>& rows, Scene& s)
{
  s.start.assign(rows.size() + 1, 0);
  s.nbr.clear();
  for (size_t i = 0; i < rows.size(); ++i) {
    s.nbr.insert(s.nbr.end(), rows[i].begin(), rows[i].end());
    s.start[i + 1] = s.nbr.size();
  }
}

Scene
grid_scene(int w, int h)
{
  Scene s;
  std::vector<std::vector<int32_t>> rows;
  add_grid(s.xyz, rows, s.component, w, h, 0.0, 0);
  rows_to_csr(rows, s);
  s.finish();
  return s;
}

// Random points on a wavy surface, symmetrized brute-force k-NN adjacency,
// components labelled by BFS (numbered by lowest point, as dacpo_knn does).
Scene
random_knn_scene(size_t count, size_t k, uint32_t seed)
{
  Scene s;
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t i = 0; i < count; ++i) {
    double x = u(gen) * 4.0, y = u(gen) * 2.0;
    s.xyz.push_back(x);
    s.xyz.push_back(y);
    s.xyz.push_back(0.2 * std::sin(3.0 * x) * std::cos(2.0 * y));
  }
  std::vector<std::set<int32_t>> sets(count);
  std::vector<std::pair<double, int32_t>> d(count);
  for (size_t i = 0; i < count; ++i) {
    for (size_t j = 0; j < count; ++j) {
      double dx = s.xyz[3 * i] - s.xyz[3 * j], dy = s.xyz[3 * i + 1] - s.xyz[3 * j + 1],
             dz = s.xyz[3 * i + 2] - s.xyz[3 * j + 2];
      d[j] = {dx * dx + dy * dy + dz * dz, (int32_t)j};
    }
    std::partial_sort(d.begin(), d.begin() + (long)k + 1, d.end());
    for (size_t t = 0; t <= k; ++t)
      if (d[t].second != (int32_t)i) {
        sets[i].insert(d[t].second);
        sets[(size_t)d[t].second].insert((int32_t)i);
      }
  }
  std::vector<std::vector<int32_t>> rows(count);
  for (size_t i = 0; i < count; ++i)
    rows[i].assign(sets[i].begin(), sets[i].end());
  rows_to_csr(rows, s);
  s.component.assign(count, -1);
  int32_t nc = 0;
  for (size_t i = 0; i < count; ++i) {
    if (s.component[i] >= 0)
      continue;
    std::deque<int32_t> q{(int32_t)i};
    s.component[i] = nc;
    while (!q.empty()) {
      int32_t p = q.front();
      q.pop_front();
      for (int32_t r : rows[(size_t)p])
        if (s.component[(size_t)r] < 0) {
          s.component[(size_t)r] = nc;
          q.push_back(r);
        }
    }
    ++nc;
  }
  s.num_components = (size_t)nc;
  s.finish();
  return s;
}

// Hop distance from the set `src` over adj, restricted to component comp,
// up to max_hops (-1 = farther / unreachable).
std::vector<int>
hop_distance(const Scene& s,
             const std::vector<int32_t>& src,
             int32_t comp,
             int max_hops)
{
  std::vector<int> dist(s.n(), -1);
  std::deque<int32_t> q;
  for (int32_t p : src) {
    dist[(size_t)p] = 0;
    q.push_back(p);
  }
  while (!q.empty()) {
    int32_t p = q.front();
    q.pop_front();
    if (dist[(size_t)p] == max_hops)
      continue;
    for (size_t e = s.start[(size_t)p]; e < s.start[(size_t)p + 1]; ++e) {
      int32_t r = s.nbr[e];
      if (dist[(size_t)r] < 0 && s.component[(size_t)r] == comp) {
        dist[(size_t)r] = dist[(size_t)p] + 1;
        q.push_back(r);
      }
    }
  }
  return dist;
}

// Checks every structural promise of dacpo_blocks; rings against brute-force BFS.
void
expect_valid(const Scene& s, const dacpo_blocks& b, size_t ring_hops)
{
  const size_t n = s.n();
  ASSERT_GT(b.num_blocks, 0u);
  ASSERT_NE(b.block_of, nullptr);
  ASSERT_NE(b.own, nullptr);
  ASSERT_NE(b.own_start, nullptr);
  ASSERT_NE(b.ring_start, nullptr);
  ASSERT_NE(b.component_of_block, nullptr);
  ASSERT_EQ(b.own_start[0], 0u);
  ASSERT_EQ(b.own_start[b.num_blocks], n);
  ASSERT_EQ(b.ring_start[0], 0u);
  std::vector<int> seen(n, 0);
  for (size_t k = 0; k < b.num_blocks; ++k) {
    ASSERT_LT(b.own_start[k], b.own_start[k + 1]) << "block " << k << " is empty";
    if (k > 0) { // numbered component by component
      EXPECT_LE(b.component_of_block[k - 1], b.component_of_block[k]);
    }
    for (size_t t = b.own_start[k]; t < b.own_start[k + 1]; ++t) {
      int32_t p = b.own[t];
      ASSERT_GE(p, 0);
      ASSERT_LT((size_t)p, n);
      if (t > b.own_start[k]) {
        EXPECT_LT(b.own[t - 1], p) << "own list of block " << k << " not ascending";
      }
      EXPECT_EQ(b.block_of[p], (int32_t)k);
      EXPECT_EQ(s.component[(size_t)p], b.component_of_block[k]);
      seen[(size_t)p]++;
    }
  }
  for (size_t i = 0; i < n; ++i)
    ASSERT_EQ(seen[i], 1) << "point " << i;

  for (size_t k = 0; k < b.num_blocks; ++k) {
    // Connected inside the block.
    std::vector<int32_t> own(b.own + b.own_start[k], b.own + b.own_start[k + 1]);
    std::vector<char> vis(n, 0);
    std::deque<int32_t> q{own[0]};
    vis[(size_t)own[0]] = 1;
    size_t reached = 1;
    while (!q.empty()) {
      int32_t p = q.front();
      q.pop_front();
      for (size_t e = s.start[(size_t)p]; e < s.start[(size_t)p + 1]; ++e) {
        int32_t r = s.nbr[e];
        if (!vis[(size_t)r] && b.block_of[r] == (int32_t)k) {
          vis[(size_t)r] = 1;
          ++reached;
          q.push_back(r);
        }
      }
    }
    EXPECT_EQ(reached, own.size()) << "block " << k << " is not connected";

    // Ring: points of other blocks within ring_hops hops.
    std::vector<int32_t> ring(b.ring + b.ring_start[k], b.ring + b.ring_start[k + 1]);
    EXPECT_TRUE(std::is_sorted(ring.begin(), ring.end()));
    if (ring_hops == 0) {
      EXPECT_TRUE(ring.empty());
      continue;
    }
    std::vector<int> dist =
        hop_distance(s, own, b.component_of_block[k], (int)ring_hops);
    std::vector<int32_t> want;
    for (size_t i = 0; i < n; ++i)
      if (dist[i] >= 1)
        want.push_back((int32_t)i);
    EXPECT_EQ(ring, want) << "ring of block " << k;
  }
}

std::vector<size_t>
block_sizes(const dacpo_blocks& b)
{
  std::vector<size_t> sz;
  for (size_t k = 0; k < b.num_blocks; ++k)
    sz.push_back(b.own_start[k + 1] - b.own_start[k]);
  return sz;
}

// A w x h grid folded at a right angle after column fold: columns < fold lie
// in z = 0 (axis +z), the others stand at x = fold (axis +x). The adjacency
// is the grid's, whatever the fold.
Scene
folded_grid_scene(int w, int h, int fold)
{
  Scene s = grid_scene(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = fold; x < w; ++x) {
      double* p = &s.xyz[3 * (size_t)(y * w + x)];
      p[0] = fold;
      p[2] = x - fold + 1;
    }
  for (size_t i = 0; i < s.n(); ++i)
    s.nrm[3 * i + (s.xyz[3 * i] < fold ? 2 : 0)] = 1.0;
  return s;
}

// Blocks holding points of both faces of a folded grid.
size_t
blocks_across_fold(const Scene& s, const dacpo_blocks& b, int fold)
{
  size_t mixed = 0;
  for (size_t k = 0; k < b.num_blocks; ++k) {
    bool flat = false, standing = false;
    for (size_t t = b.own_start[k]; t < b.own_start[k + 1]; ++t)
      (s.xyz[3 * (size_t)b.own[t]] < fold ? flat : standing) = true;
    mixed += flat && standing;
  }
  return mixed;
}

} // namespace

TEST(DacpoSegment, CreaseAxesPutTheBlockBorderOnTheFold)
{
  // 24 flat and 16 standing columns, 2 blocks: the median split leaves 4 flat
  // columns with the standing face, whose seed is on the standing face. Hop
  // distance puts the border midway between the seeds, on the flat face;
  // a step across the fold costs 21 hops, so the crease growth stops there.
  Scene s = folded_grid_scene(40, 8, 24);
  dacpo_err err{};
  dacpo_blocks plain{}, creased{};
  ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 2, 1, &plain, &err),
            DACPO_OK)
      << err.msg;
  ASSERT_EQ(dacpo_segment_creased(
                &s.cloud, &s.adj, s.nrm.data(), s.component.data(), 1, 2, 1, &creased, &err),
            DACPO_OK)
      << err.msg;
  ASSERT_EQ(plain.num_blocks, 2u);
  ASSERT_EQ(creased.num_blocks, 2u);
  EXPECT_EQ(blocks_across_fold(s, plain, 24), 1u);
  EXPECT_EQ(blocks_across_fold(s, creased, 24), 0u);
  expect_valid(s, creased, 1);
  dacpo_blocks_free(&plain);
  dacpo_blocks_free(&creased);
}

TEST(DacpoSegment, CreaseGrowthOnAFlatSurfaceIsTheBfs)
{
  // Equal axes everywhere: every step costs 1, so the shortest paths are the
  // BFS's hop counts and the blocks are the same (ties go to the lower index
  // in both: the BFS by queue order, which follows the seed order).
  Scene s = grid_scene(60, 40);
  for (size_t i = 0; i < s.n(); ++i)
    s.nrm[3 * i + 2] = 1.0;
  dacpo_err err{};
  dacpo_blocks plain{}, creased{};
  ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 6, 2, &plain, &err),
            DACPO_OK);
  ASSERT_EQ(dacpo_segment_creased(
                &s.cloud, &s.adj, s.nrm.data(), s.component.data(), 1, 6, 2, &creased, &err),
            DACPO_OK);
  ASSERT_EQ(plain.num_blocks, creased.num_blocks);
  size_t differ = 0;
  for (size_t i = 0; i < s.n(); ++i)
    differ += plain.block_of[i] != creased.block_of[i];
  // only points at equal distance from two seeds may go either way
  EXPECT_LE(differ, s.n() / 20);
  expect_valid(s, creased, 2);
  dacpo_blocks_free(&plain);
  dacpo_blocks_free(&creased);
}

TEST(DacpoSegment, GridSplitsIntoSixteenConnectedEqualBlocks)
{
  Scene s = grid_scene(100, 100);
  dacpo_blocks b{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 16, 2, &b, &err),
            DACPO_OK)
      << err.msg;
  EXPECT_EQ(b.num_blocks, 16u);
  for (size_t sz : block_sizes(b)) {
    EXPECT_GE(sz, 625u / 2);
    EXPECT_LE(sz, 625u * 2);
  }
  expect_valid(s, b, 2);
  dacpo_blocks_free(&b);
}

TEST(DacpoSegment, TwoComponentsGetDisjointProportionalBlocks)
{
  Scene s;
  std::vector<std::vector<int32_t>> rows;
  add_grid(s.xyz, rows, s.component, 60, 60, 0.0, 0);   // 3600 points
  add_grid(s.xyz, rows, s.component, 30, 30, 500.0, 1); // 900 points, far away
  rows_to_csr(rows, s);
  s.num_components = 2;
  s.finish();
  dacpo_blocks b{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 2, 10, 1, &b, &err),
            DACPO_OK)
      << err.msg;
  // round(10 * 3600 / 4500) = 8 and round(10 * 900 / 4500) = 2
  ASSERT_EQ(b.num_blocks, 10u);
  for (size_t k = 0; k < 10; ++k)
    EXPECT_EQ(b.component_of_block[k], k < 8 ? 0 : 1) << "block " << k;
  expect_valid(s, b, 1);
  // Rings never cross components.
  for (size_t k = 0; k < b.num_blocks; ++k)
    for (size_t t = b.ring_start[k]; t < b.ring_start[k + 1]; ++t)
      EXPECT_EQ(s.component[(size_t)b.ring[t]], b.component_of_block[k]);
  dacpo_blocks_free(&b);
}

TEST(DacpoSegment, RingIsExactlyOtherBlocksWithinHops)
{
  Scene s = grid_scene(20, 20);
  for (size_t hops = 1; hops <= 4; ++hops) {
    dacpo_blocks b{};
    dacpo_err err{};
    ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 8, hops, &b, &err),
              DACPO_OK)
        << err.msg;
    EXPECT_EQ(b.num_blocks, 8u);
    expect_valid(s, b, hops);
    // On a grid a 1-hop ring is non-empty for every block (the grid is connected).
    for (size_t k = 0; k < b.num_blocks; ++k)
      EXPECT_GT(b.ring_start[k + 1], b.ring_start[k]);
    dacpo_blocks_free(&b);
  }
}

TEST(DacpoSegment, RingMatchesBruteForceOnKnnGraph)
{
  Scene s = random_knn_scene(1500, 8, 7);
  dacpo_blocks b{};
  dacpo_err err{};
  ASSERT_EQ(
      dacpo_segment(
          &s.cloud, &s.adj, s.component.data(), s.num_components, 12, 3, &b, &err),
      DACPO_OK)
      << err.msg;
  EXPECT_GE(b.num_blocks, 12u);
  expect_valid(s, b, 3);
  dacpo_blocks_free(&b);
}

TEST(DacpoSegment, ZeroHopsGivesEmptyRings)
{
  Scene s = grid_scene(30, 30);
  dacpo_blocks b{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 5, 0, &b, &err),
            DACPO_OK)
      << err.msg;
  EXPECT_EQ(b.num_blocks, 5u);
  EXPECT_EQ(b.ring_start[b.num_blocks], 0u);
  expect_valid(s, b, 0);
  dacpo_blocks_free(&b);
}

TEST(DacpoSegment, TargetLargerThanPossibleStaysValid)
{
  {
    Scene s = grid_scene(10, 1); // 10 points on a line, 50 blocks asked
    dacpo_blocks b{};
    dacpo_err err{};
    ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 50, 2, &b, &err),
              DACPO_OK)
        << err.msg;
    EXPECT_EQ(b.num_blocks, 1u); // capped at max(1, 10 / 8)
    expect_valid(s, b, 2);
    dacpo_blocks_free(&b);
  }
  {
    Scene s = grid_scene(8, 5); // 40 points, 1000 blocks asked: cap 40 / 8 = 5
    dacpo_blocks b{};
    dacpo_err err{};
    ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 1000, 2, &b, &err),
              DACPO_OK)
        << err.msg;
    EXPECT_EQ(b.num_blocks, 5u);
    expect_valid(s, b, 2);
    dacpo_blocks_free(&b);
  }
}

TEST(DacpoSegment, SinglePointComponentGetsItsOwnBlock)
{
  Scene s;
  std::vector<std::vector<int32_t>> rows;
  add_grid(s.xyz, rows, s.component, 1, 1, -50.0, 0); // isolated point 0
  add_grid(s.xyz, rows, s.component, 40, 40, 0.0, 1);
  rows_to_csr(rows, s);
  s.num_components = 2;
  s.finish();
  dacpo_blocks b{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 2, 4, 2, &b, &err),
            DACPO_OK)
      << err.msg;
  // round(4 * 1 / 1601) = 0 -> 1 block; round(4 * 1600 / 1601) = 4
  ASSERT_EQ(b.num_blocks, 5u);
  EXPECT_EQ(b.component_of_block[0], 0);
  EXPECT_EQ(b.own_start[1], 1u);
  EXPECT_EQ(b.own[0], 0);
  EXPECT_EQ(b.ring_start[1], 0u); // nothing within reach of an isolated point
  expect_valid(s, b, 2);
  dacpo_blocks_free(&b);
}

TEST(DacpoSegment, TargetZeroMeansOneBlockPerComponent)
{
  Scene s;
  std::vector<std::vector<int32_t>> rows;
  add_grid(s.xyz, rows, s.component, 20, 20, 0.0, 0);
  add_grid(s.xyz, rows, s.component, 10, 10, 100.0, 1);
  rows_to_csr(rows, s);
  s.num_components = 2;
  s.finish();
  dacpo_blocks b{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 2, 0, 3, &b, &err),
            DACPO_OK)
      << err.msg;
  ASSERT_EQ(b.num_blocks, 2u);
  EXPECT_EQ(b.own_start[1], 400u);
  EXPECT_EQ(b.ring_start[2], 0u); // whole components: no other block in reach
  expect_valid(s, b, 3);
  dacpo_blocks_free(&b);
}

// The paper's "no segmentation" ablation is target 0: one block per non-empty
// component, numbered in component order, own points ascending.
TEST(DacpoSegment, SingleBlockPerComponentAblation)
{
  Scene s;
  std::vector<std::vector<int32_t>> rows;
  add_grid(s.xyz, rows, s.component, 5, 5, 0.0, 1); // labels 1 then 0: order by label
  add_grid(s.xyz, rows, s.component, 3, 3, 100.0, 0);
  rows_to_csr(rows, s);
  s.num_components = 3; // component 2 has no points: no block
  s.finish();
  dacpo_blocks b{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 3, 0, 0, &b, &err),
            DACPO_OK)
      << err.msg;
  ASSERT_EQ(b.num_blocks, 2u);
  EXPECT_EQ(b.component_of_block[0], 0);
  EXPECT_EQ(b.component_of_block[1], 1);
  EXPECT_EQ(b.own_start[1], 9u);
  EXPECT_EQ(b.own[0], 25);
  EXPECT_EQ(b.block_of[0], 1);
  expect_valid(s, b, 0);
  dacpo_blocks_free(&b);
}

TEST(DacpoSegment, RunsAreDeterministic)
{
  Scene s = random_knn_scene(1200, 6, 3);
  dacpo_blocks a{}, b{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_segment(
                &s.cloud, &s.adj, s.component.data(), s.num_components, 9, 2, &a, &err),
            DACPO_OK);
  ASSERT_EQ(dacpo_segment(
                &s.cloud, &s.adj, s.component.data(), s.num_components, 9, 2, &b, &err),
            DACPO_OK);
  ASSERT_EQ(a.num_blocks, b.num_blocks);
  const size_t n = s.n();
  EXPECT_EQ(0, std::memcmp(a.block_of, b.block_of, n * sizeof(int32_t)));
  EXPECT_EQ(0, std::memcmp(a.own, b.own, n * sizeof(int32_t)));
  EXPECT_EQ(
      0, std::memcmp(a.ring_start, b.ring_start, (a.num_blocks + 1) * sizeof(size_t)));
  EXPECT_EQ(0,
            std::memcmp(a.ring, b.ring, a.ring_start[a.num_blocks] * sizeof(int32_t)));
  dacpo_blocks_free(&a);
  dacpo_blocks_free(&b);
}

TEST(DacpoSegment, MislabelledComponentStillLabelsEveryPoint)
{
  // Two separate grids labelled as one component: the seeds may all fall in one
  // piece; the other must still get (connected) blocks of its own.
  Scene s;
  std::vector<std::vector<int32_t>> rows;
  add_grid(s.xyz, rows, s.component, 30, 30, 0.0, 0);
  add_grid(s.xyz, rows, s.component, 4, 4, 1000.0, 0);
  rows_to_csr(rows, s);
  s.finish();
  dacpo_blocks b{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 1, 1, &b, &err),
            DACPO_OK)
      << err.msg;
  EXPECT_EQ(b.num_blocks, 2u);
  expect_valid(s, b, 1);
  dacpo_blocks_free(&b);
}

TEST(DacpoSegment, BadArgumentsAreRejected)
{
  Scene s = grid_scene(5, 5);
  dacpo_blocks b{};
  dacpo_err err{};
  EXPECT_EQ(dacpo_segment(nullptr, &s.adj, s.component.data(), 1, 2, 1, &b, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_segment(&s.cloud, nullptr, s.component.data(), 1, 2, 1, &b, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 2, 1, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_segment(&s.cloud, &s.adj, nullptr, 1, 2, 1, &b, &err),
            DACPO_ERR_INVALID_ARGUMENT);

  s.component[7] = 3; // outside [0, 1)
  EXPECT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 2, 1, &b, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::strstr(err.msg, "point 7"), nullptr) << err.msg;
  EXPECT_EQ(b.block_of, nullptr);
  s.component[7] = 0;

  s.adj.n = 24;
  EXPECT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 2, 1, &b, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  s.adj.n = 25;
  s.nbr[3] = 99;
  EXPECT_EQ(dacpo_segment(&s.cloud, &s.adj, s.component.data(), 1, 2, 1, &b, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(b.num_blocks, 0u);

  dacpo_blocks_free(nullptr); // NULL-safe
  dacpo_blocks_free(&b);
}
