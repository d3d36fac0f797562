// SPDX-License-Identifier: BSD-3-Clause
// Bridges between the components of a disconnected adjacency: the minimum
// spanning tree over components (checked against a brute-force Kruskal with the
// same (distance, lower index, higher index) order), the extra cross pairs, the
// CSR conventions, and bad arguments.
extern "C" {
#include "dacpo_bridge.h"
}

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace {

using Pair = std::pair<int32_t, int32_t>; // (lower, higher) point index

struct Cloud {
  dacpo_cloud c{};
  Cloud() = default;
  Cloud(const Cloud&) = delete;
  Cloud&
  operator=(const Cloud&) = delete;
  ~Cloud() { dacpo_cloud_free(&c); }
};

struct Adj {
  dacpo_adjacency a{};
  Adj() = default;
  Adj(const Adj&) = delete;
  Adj&
  operator=(const Adj&) = delete;
  ~Adj() { dacpo_adjacency_free(&a); }
};

void
buildCloud(const std::vector<float>& xyz, Cloud* cl)
{
  dacpo_err err{};
  ASSERT_EQ(dacpo_cloud_build(xyz.data(), nullptr, xyz.size() / 3, &cl->c, &err),
            DACPO_OK)
      << err.msg;
  ASSERT_EQ(cl->c.n, xyz.size() / 3) << "test points must be distinct";
}

// The symmetrized k-NN adjacency and its components, as the pipeline makes them.
void
knnAdjacency(
    const Cloud& cl, size_t k, Adj* adj, std::vector<int32_t>* label, size_t* nc)
{
  dacpo_err err{};
  dacpo_knn_graph g{};
  ASSERT_EQ(dacpo_knn_build(&cl.c, k, nullptr, 1, nullptr, &g, &err), DACPO_OK)
      << err.msg;
  ASSERT_EQ(dacpo_adjacency_build(&g, k, &adj->a, &err), DACPO_OK) << err.msg;
  dacpo_knn_graph_free(&g);
  label->assign(cl.c.n, -1);
  ASSERT_EQ(dacpo_components_label(&adj->a, label->data(), nc, &err), DACPO_OK)
      << err.msg;
}

// CSR from an undirected edge list (rows sorted), components labelled.
void
edgeAdjacency(size_t n,
              const std::vector<Pair>& edges,
              Adj* adj,
              std::vector<int32_t>* label,
              size_t* nc)
{
  std::vector<std::vector<int32_t>> rows(n);
  for (const Pair& e : edges) {
    rows[e.first].push_back(e.second);
    rows[e.second].push_back(e.first);
  }
  adj->a.n = n;
  adj->a.start = static_cast<size_t*>(malloc((n + 1) * sizeof(size_t)));
  adj->a.nbr = static_cast<int32_t*>(malloc((2 * edges.size() + 1) * sizeof(int32_t)));
  adj->a.start[0] = 0;
  for (size_t i = 0; i < n; ++i) {
    std::sort(rows[i].begin(), rows[i].end());
    std::copy(rows[i].begin(), rows[i].end(), adj->a.nbr + adj->a.start[i]);
    adj->a.start[i + 1] = adj->a.start[i] + rows[i].size();
  }
  dacpo_err err{};
  label->assign(n, -1);
  ASSERT_EQ(dacpo_components_label(&adj->a, label->data(), nc, &err), DACPO_OK)
      << err.msg;
}

double
dist2(const dacpo_cloud& c, int32_t a, int32_t b)
{
  const double* x = c.xyz + 3 * static_cast<size_t>(a);
  const double* y = c.xyz + 3 * static_cast<size_t>(b);
  double dx = x[0] - y[0], dy = x[1] - y[1], dz = x[2] - y[2];
  return dx * dx + dy * dy + dz * dz;
}

// Rows strictly ascending, no self loop, indices in range, symmetric.
void
expectValidCsr(const dacpo_adjacency& a)
{
  ASSERT_NE(a.start, nullptr);
  EXPECT_EQ(a.start[0], 0u);
  std::set<Pair> directed;
  for (size_t i = 0; i < a.n; ++i) {
    for (size_t e = a.start[i]; e < a.start[i + 1]; ++e) {
      int32_t j = a.nbr[e];
      ASSERT_GE(j, 0);
      ASSERT_LT(static_cast<size_t>(j), a.n);
      EXPECT_NE(static_cast<size_t>(j), i) << "self loop at " << i;
      if (e > a.start[i]) {
        EXPECT_LT(a.nbr[e - 1], j) << "row " << i << " not strictly ascending";
      }
      directed.insert({static_cast<int32_t>(i), j});
    }
  }
  for (const Pair& d : directed)
    EXPECT_TRUE(directed.count({d.second, d.first})) << d.first << "->" << d.second;
}

bool
isConnected(const dacpo_adjacency& a)
{
  if (a.n == 0)
    return true;
  std::vector<char> seen(a.n, 0);
  std::vector<int32_t> queue{0};
  seen[0] = 1;
  for (size_t h = 0; h < queue.size(); ++h)
    for (size_t e = a.start[queue[h]]; e < a.start[queue[h] + 1]; ++e)
      if (!seen[a.nbr[e]]) {
        seen[a.nbr[e]] = 1;
        queue.push_back(a.nbr[e]);
      }
  return queue.size() == a.n;
}

std::set<Pair>
edgeSet(const dacpo_adjacency& a)
{
  std::set<Pair> s;
  for (size_t i = 0; i < a.n; ++i)
    for (size_t e = a.start[i]; e < a.start[i + 1]; ++e)
      if (static_cast<int32_t>(i) < a.nbr[e])
        s.insert({static_cast<int32_t>(i), a.nbr[e]});
  return s;
}

// Edges of `out` that are not in `in` (and a check that `in` is kept whole).
std::set<Pair>
addedEdges(const dacpo_adjacency& in, const dacpo_adjacency& out)
{
  std::set<Pair> a = edgeSet(in), b = edgeSet(out), added;
  for (const Pair& e : a)
    EXPECT_TRUE(b.count(e)) << "edge " << e.first << "-" << e.second << " lost";
  for (const Pair& e : b)
    if (!a.count(e))
      added.insert(e);
  return added;
}

// Brute-force MST over components: the closest pair of every component pair
// under the (d2, lower, higher) order, then Kruskal.
std::set<Pair>
bruteForceTree(const dacpo_cloud& c, const std::vector<int32_t>& label, size_t nc)
{
  using Key = std::tuple<double, int32_t, int32_t>;
  const Key none{INFINITY, INT32_MAX, INT32_MAX};
  std::vector<Key> best(nc * nc, none);
  for (int32_t i = 0; i < static_cast<int32_t>(c.n); ++i)
    for (int32_t j = i + 1; j < static_cast<int32_t>(c.n); ++j) {
      int32_t a = label[i], b = label[j];
      if (a == b)
        continue;
      size_t slot = static_cast<size_t>(std::min(a, b)) * nc + std::max(a, b);
      best[slot] = std::min(best[slot], Key{dist2(c, i, j), i, j});
    }
  std::vector<Key> order;
  for (const Key& k : best)
    if (k != none)
      order.push_back(k);
  std::sort(order.begin(), order.end());
  std::vector<int32_t> parent(nc);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int32_t x) {
    while (parent[x] != x)
      x = parent[x] = parent[parent[x]];
    return x;
  };
  std::set<Pair> tree;
  for (const Key& k : order) {
    int32_t a = find(label[std::get<1>(k)]), b = find(label[std::get<2>(k)]);
    if (a != b) {
      parent[a] = b;
      tree.insert({std::get<1>(k), std::get<2>(k)});
    }
  }
  return tree;
}

// n points uniform in a cube of side `size` at `origin`.
void
addBlob(std::vector<float>* xyz,
        std::mt19937* rng,
        size_t n,
        double ox,
        double oy,
        double oz,
        double size)
{
  std::uniform_real_distribution<double> u(0.0, size);
  for (size_t i = 0; i < n; ++i) {
    xyz->push_back(static_cast<float>(ox + u(*rng)));
    xyz->push_back(static_cast<float>(oy + u(*rng)));
    xyz->push_back(static_cast<float>(oz + u(*rng)));
  }
}

struct Result {
  dacpo_status status;
  Adj out;
  size_t added = 0;
  double longest = -1.0;
  std::vector<int32_t> label;
  dacpo_err err{};
};

void
runBridge(const Cloud& cl,
          const Adj& adj,
          const std::vector<int32_t>& label,
          size_t nc,
          size_t extra,
          Result* r)
{
  r->label = label;
  r->status = dacpo_bridge_components(&cl.c,
                                      &adj.a,
                                      r->label.data(),
                                      nc,
                                      extra,
                                      &r->out.a,
                                      &r->added,
                                      &r->longest,
                                      &r->err);
}

} // namespace

TEST(DacpoBridge, TwoFarClustersGetOneBridgeAtTheClosestPair)
{
  std::mt19937 rng(11);
  std::vector<float> xyz;
  addBlob(&xyz, &rng, 300, 0.0, 0.0, 0.0, 1.0);
  addBlob(&xyz, &rng, 250, 4.0, 0.5, 0.2, 1.0);
  Cloud cl;
  buildCloud(xyz, &cl);
  Adj adj;
  std::vector<int32_t> label;
  size_t nc = 0;
  knnAdjacency(cl, 10, &adj, &label, &nc);
  ASSERT_EQ(nc, 2u);

  Result r;
  runBridge(cl, adj, label, nc, 0, &r);
  ASSERT_EQ(r.status, DACPO_OK) << r.err.msg;
  EXPECT_EQ(r.added, 1u);
  expectValidCsr(r.out.a);
  EXPECT_TRUE(isConnected(r.out.a));
  EXPECT_TRUE(
      std::all_of(r.label.begin(), r.label.end(), [](int32_t l) { return l == 0; }));

  // Brute force closest cross pair.
  double bd = INFINITY;
  Pair bp{-1, -1};
  for (int32_t i = 0; i < static_cast<int32_t>(cl.c.n); ++i)
    for (int32_t j = i + 1; j < static_cast<int32_t>(cl.c.n); ++j)
      if (label[i] != label[j] && dist2(cl.c, i, j) < bd) {
        bd = dist2(cl.c, i, j);
        bp = {i, j};
      }
  std::set<Pair> added = addedEdges(adj.a, r.out.a);
  ASSERT_EQ(added.size(), 1u);
  EXPECT_EQ(*added.begin(), bp);
  EXPECT_DOUBLE_EQ(r.longest, std::sqrt(bd));
}

TEST(DacpoBridge, ThreeCollinearClustersBridgeNeighboursOnly)
{
  std::mt19937 rng(5);
  std::vector<float> xyz;
  addBlob(&xyz, &rng, 200, 0.0, 0.0, 0.0, 1.0);  // A
  addBlob(&xyz, &rng, 200, 5.0, 0.0, 0.0, 1.0);  // B
  addBlob(&xyz, &rng, 200, 10.0, 0.0, 0.0, 1.0); // C
  Cloud cl;
  buildCloud(xyz, &cl);
  Adj adj;
  std::vector<int32_t> label;
  size_t nc = 0;
  knnAdjacency(cl, 10, &adj, &label, &nc);
  ASSERT_EQ(nc, 3u);

  Result r;
  runBridge(cl, adj, label, nc, 0, &r);
  ASSERT_EQ(r.status, DACPO_OK) << r.err.msg;
  EXPECT_EQ(r.added, 2u);
  expectValidCsr(r.out.a);
  EXPECT_TRUE(isConnected(r.out.a));
  // Components are numbered by lowest index: A = 0, B = 1, C = 2.
  std::set<Pair> joined;
  for (const Pair& e : addedEdges(adj.a, r.out.a))
    joined.insert({std::min(label[e.first], label[e.second]),
                   std::max(label[e.first], label[e.second])});
  EXPECT_EQ(joined, (std::set<Pair>{{0, 1}, {1, 2}}));
  EXPECT_LT(r.longest, 5.0);
  EXPECT_GT(r.longest, 3.0);
}

TEST(DacpoBridge, SingleComponentIsUnchanged)
{
  std::mt19937 rng(3);
  std::vector<float> xyz;
  addBlob(&xyz, &rng, 400, 0.0, 0.0, 0.0, 1.0);
  Cloud cl;
  buildCloud(xyz, &cl);
  Adj adj;
  std::vector<int32_t> label;
  size_t nc = 0;
  knnAdjacency(cl, 10, &adj, &label, &nc);
  ASSERT_EQ(nc, 1u);

  Result r;
  runBridge(cl, adj, label, nc, 3, &r);
  ASSERT_EQ(r.status, DACPO_OK) << r.err.msg;
  EXPECT_EQ(r.added, 0u);
  EXPECT_EQ(r.longest, 0.0);
  ASSERT_EQ(r.out.a.n, adj.a.n);
  ASSERT_NE(r.out.a.start, adj.a.start) << "must be a copy the caller frees";
  EXPECT_TRUE(std::equal(adj.a.start, adj.a.start + adj.a.n + 1, r.out.a.start));
  EXPECT_TRUE(std::equal(adj.a.nbr, adj.a.nbr + adj.a.start[adj.a.n], r.out.a.nbr));
  EXPECT_EQ(r.label, label);
}

TEST(DacpoBridge, ManySpecksFollowTheMinimumSpanningTree)
{
  // 500 specks of 1..4 points (a chain inside each) scattered in a box.
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> pos(0.0, 10.0), jit(0.0, 0.02);
  std::uniform_int_distribution<int> size(1, 4);
  std::vector<float> xyz;
  std::vector<Pair> edges;
  for (int s = 0; s < 500; ++s) {
    double x = pos(rng), y = pos(rng), z = pos(rng);
    int m = size(rng);
    for (int i = 0; i < m; ++i) {
      int32_t id = static_cast<int32_t>(xyz.size() / 3);
      if (i > 0)
        edges.push_back({id - 1, id});
      xyz.push_back(static_cast<float>(x + jit(rng)));
      xyz.push_back(static_cast<float>(y + jit(rng)));
      xyz.push_back(static_cast<float>(z + jit(rng)));
    }
  }
  Cloud cl;
  buildCloud(xyz, &cl);
  Adj adj;
  std::vector<int32_t> label;
  size_t nc = 0;
  edgeAdjacency(cl.c.n, edges, &adj, &label, &nc);
  ASSERT_EQ(nc, 500u);

  Result r;
  runBridge(cl, adj, label, nc, 0, &r);
  ASSERT_EQ(r.status, DACPO_OK) << r.err.msg;
  EXPECT_EQ(r.added, nc - 1);
  expectValidCsr(r.out.a);
  EXPECT_TRUE(isConnected(r.out.a));
  std::set<Pair> added = addedEdges(adj.a, r.out.a);
  std::set<Pair> tree = bruteForceTree(cl.c, label, nc);
  EXPECT_EQ(added, tree);
  double longest = 0.0;
  for (const Pair& e : tree)
    longest = std::max(longest, std::sqrt(dist2(cl.c, e.first, e.second)));
  EXPECT_DOUBLE_EQ(r.longest, longest);

  // With extra pairs the tree is still there and the graph stays valid.
  Result rx;
  runBridge(cl, adj, label, nc, 2, &rx);
  ASSERT_EQ(rx.status, DACPO_OK) << rx.err.msg;
  expectValidCsr(rx.out.a);
  std::set<Pair> addedx = addedEdges(adj.a, rx.out.a);
  EXPECT_EQ(addedx.size(), rx.added);
  EXPECT_TRUE(std::includes(addedx.begin(), addedx.end(), tree.begin(), tree.end()));
  EXPECT_GT(rx.added, nc - 1);
  EXPECT_LE(rx.added, 3 * (nc - 1));
}

TEST(DacpoBridge, KnnClustersMatchBruteForceTree)
{
  // 40 blobs of 20..80 points: the k-NN components of a noisy scene.
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> pos(0.0, 30.0);
  std::uniform_int_distribution<int> size(20, 80);
  std::vector<float> xyz;
  for (int b = 0; b < 40; ++b)
    addBlob(&xyz, &rng, size(rng), pos(rng), pos(rng), pos(rng) * 0.2, 0.5);
  Cloud cl;
  buildCloud(xyz, &cl);
  Adj adj;
  std::vector<int32_t> label;
  size_t nc = 0;
  knnAdjacency(cl, 10, &adj, &label, &nc);
  ASSERT_GE(nc, 30u);

  Result r;
  runBridge(cl, adj, label, nc, 0, &r);
  ASSERT_EQ(r.status, DACPO_OK) << r.err.msg;
  EXPECT_EQ(r.added, nc - 1);
  expectValidCsr(r.out.a);
  EXPECT_TRUE(isConnected(r.out.a));
  EXPECT_EQ(addedEdges(adj.a, r.out.a), bruteForceTree(cl.c, label, nc));
}

TEST(DacpoBridge, TiesAreBrokenByLowestIndices)
{
  // Two 5 x 5 integer grids 3 apart in x: the five pairs of facing points all
  // lie at distance exactly 3. Points are listed in a shuffled order.
  std::vector<std::array<float, 3>> pts;
  for (int g = 0; g < 2; ++g)
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 5; ++x)
        pts.push_back({static_cast<float>(x + 7 * g), static_cast<float>(y), 0.0f});
  std::vector<int32_t> perm(pts.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::mt19937 rng(2);
  std::shuffle(perm.begin(), perm.end(), rng);
  std::vector<float> xyz;
  for (int32_t p : perm)
    xyz.insert(xyz.end(), pts[p].begin(), pts[p].end());
  std::vector<Pair> edges; // 4-neighbour grid edges, in shuffled indices
  std::vector<int32_t> where(pts.size());
  for (size_t i = 0; i < perm.size(); ++i)
    where[perm[i]] = static_cast<int32_t>(i);
  for (int g = 0; g < 2; ++g)
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 5; ++x) {
        int id = g * 25 + y * 5 + x;
        if (x < 4)
          edges.push_back(
              {std::min(where[id], where[id + 1]), std::max(where[id], where[id + 1])});
        if (y < 4)
          edges.push_back(
              {std::min(where[id], where[id + 5]), std::max(where[id], where[id + 5])});
      }
  Cloud cl;
  buildCloud(xyz, &cl);
  Adj adj;
  std::vector<int32_t> label;
  size_t nc = 0;
  edgeAdjacency(cl.c.n, edges, &adj, &label, &nc);
  ASSERT_EQ(nc, 2u);

  // Expected: among the five pairs at distance 3, the lowest (lower, higher).
  Pair expect{INT32_MAX, INT32_MAX};
  for (int y = 0; y < 5; ++y) {
    int32_t a = where[y * 5 + 4], b = where[25 + y * 5];
    expect = std::min(expect, Pair{std::min(a, b), std::max(a, b)});
  }
  Result r;
  runBridge(cl, adj, label, nc, 0, &r);
  ASSERT_EQ(r.status, DACPO_OK) << r.err.msg;
  std::set<Pair> added = addedEdges(adj.a, r.out.a);
  ASSERT_EQ(added.size(), 1u);
  EXPECT_EQ(*added.begin(), expect);
  EXPECT_DOUBLE_EQ(r.longest, 3.0);
}

TEST(DacpoBridge, ExtraAddsFurtherNearCrossPairs)
{
  std::mt19937 rng(17);
  std::vector<float> xyz;
  addBlob(&xyz, &rng, 300, 0.0, 0.0, 0.0, 1.0);
  addBlob(&xyz, &rng, 300, 2.0, 0.0, 0.0, 1.0);
  addBlob(&xyz, &rng, 300, 4.0, 0.0, 0.0, 1.0);
  Cloud cl;
  buildCloud(xyz, &cl);
  Adj adj;
  std::vector<int32_t> label;
  size_t nc = 0;
  knnAdjacency(cl, 10, &adj, &label, &nc);
  ASSERT_EQ(nc, 3u);

  Result r0, r3;
  runBridge(cl, adj, label, nc, 0, &r0);
  runBridge(cl, adj, label, nc, 3, &r3);
  ASSERT_EQ(r0.status, DACPO_OK) << r0.err.msg;
  ASSERT_EQ(r3.status, DACPO_OK) << r3.err.msg;
  EXPECT_EQ(r0.added, 2u);
  EXPECT_EQ(r3.added, 2u * (1 + 3));
  expectValidCsr(r3.out.a);
  std::set<Pair> tree = addedEdges(adj.a, r0.out.a);
  std::set<Pair> all = addedEdges(adj.a, r3.out.a);
  ASSERT_EQ(all.size(), 8u);
  EXPECT_TRUE(std::includes(all.begin(), all.end(), tree.begin(), tree.end()));
  for (const Pair& t : tree) {
    // The three extra pairs of this tree edge: same two components, no shorter
    // than the tree pair, nearby, and with endpoints not used twice.
    int32_t ca = std::min(label[t.first], label[t.second]);
    int32_t cb = std::max(label[t.first], label[t.second]);
    double d = std::sqrt(dist2(cl.c, t.first, t.second));
    std::set<int32_t> ends{t.first, t.second};
    size_t count = 0;
    for (const Pair& e : all) {
      if (tree.count(e))
        continue;
      if (std::min(label[e.first], label[e.second]) != ca ||
          std::max(label[e.first], label[e.second]) != cb)
        continue;
      ++count;
      double de = std::sqrt(dist2(cl.c, e.first, e.second));
      EXPECT_GE(de, d);
      EXPECT_LT(de, d + 0.5) << "extra pair far from the bridge";
      EXPECT_LT(std::sqrt(dist2(cl.c, e.first, t.first)) +
                    std::sqrt(dist2(cl.c, e.second, t.second)),
                4.0 * d + 1.0);
      EXPECT_TRUE(ends.insert(e.first).second) << "endpoint " << e.first << " reused";
      EXPECT_TRUE(ends.insert(e.second).second) << "endpoint " << e.second << " reused";
    }
    EXPECT_EQ(count, 3u);
  }
  EXPECT_GE(r3.longest, r0.longest);
}

TEST(DacpoBridge, ExtraReusesASinglePointSpeck)
{
  // A blob and one isolated point: the point's side has one candidate, so the
  // extra pairs share it; two isolated points admit only the tree pair.
  std::mt19937 rng(4);
  std::vector<float> xyz;
  addBlob(&xyz, &rng, 50, 0.0, 0.0, 0.0, 1.0);
  xyz.insert(xyz.end(), {3.0f, 0.5f, 0.5f});
  std::vector<Pair> edges;
  for (int32_t i = 1; i < 50; ++i)
    edges.push_back({i - 1, i}); // a chain through the blob
  Cloud cl;
  buildCloud(xyz, &cl);
  Adj adj;
  std::vector<int32_t> label;
  size_t nc = 0;
  edgeAdjacency(cl.c.n, edges, &adj, &label, &nc);
  ASSERT_EQ(nc, 2u);
  Result r;
  runBridge(cl, adj, label, nc, 3, &r);
  ASSERT_EQ(r.status, DACPO_OK) << r.err.msg;
  EXPECT_EQ(r.added, 4u);
  expectValidCsr(r.out.a);
  for (const Pair& e : addedEdges(adj.a, r.out.a))
    EXPECT_EQ(e.second, 50) << "every bridge touches the lone point";

  Cloud two;
  buildCloud({0.0f, 0.0f, 0.0f, 1.0f, 2.0f, 2.0f}, &two);
  Adj adj2;
  std::vector<int32_t> label2;
  size_t nc2 = 0;
  edgeAdjacency(2, {}, &adj2, &label2, &nc2);
  ASSERT_EQ(nc2, 2u);
  Result r2;
  runBridge(two, adj2, label2, nc2, 3, &r2);
  ASSERT_EQ(r2.status, DACPO_OK) << r2.err.msg;
  EXPECT_EQ(r2.added, 1u);
  EXPECT_DOUBLE_EQ(r2.longest, 3.0);
  expectValidCsr(r2.out.a);
  EXPECT_TRUE(isConnected(r2.out.a));
}

TEST(DacpoBridge, BadArgumentsAreRejected)
{
  Cloud cl;
  buildCloud({0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 5.0f, 0.0f, 0.0f}, &cl);
  Adj adj;
  std::vector<int32_t> label;
  size_t nc = 0;
  edgeAdjacency(3, {{0, 1}}, &adj, &label, &nc);
  ASSERT_EQ(nc, 2u);
  dacpo_adjacency out{};
  size_t added = 7;
  double longest = 7.0;
  dacpo_err err{};

  std::vector<int32_t> bad = {0, 0, 2}; // label out of range
  EXPECT_EQ(dacpo_bridge_components(
                &cl.c, &adj.a, bad.data(), nc, 0, &out, &added, &longest, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(err.msg).find("point 2"), std::string::npos) << err.msg;
  EXPECT_EQ(bad, (std::vector<int32_t>{0, 0, 2})) << "labels untouched on failure";
  EXPECT_EQ(out.start, nullptr);
  EXPECT_EQ(added, 0u);

  std::vector<int32_t> lab = label;
  EXPECT_EQ(dacpo_bridge_components(&cl.c,
                                    &adj.a,
                                    lab.data(),
                                    nc,
                                    DACPO_BRIDGE_MAX_EXTRA + 1,
                                    &out,
                                    &added,
                                    &longest,
                                    &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_bridge_components(
                nullptr, &adj.a, lab.data(), nc, 0, &out, &added, &longest, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_bridge_components(
                &cl.c, &adj.a, lab.data(), nc, 0, nullptr, &added, &longest, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_bridge_components(
                &cl.c, &adj.a, lab.data(), 0, 0, &out, &added, &longest, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  dacpo_adjacency wrong = adj.a;
  wrong.n = 2;
  EXPECT_EQ(dacpo_bridge_components(
                &cl.c, &wrong, lab.data(), nc, 0, &out, &added, &longest, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(lab, label);

  // And the valid call works: 0-1 joined to 2 at distance 4.
  ASSERT_EQ(dacpo_bridge_components(
                &cl.c, &adj.a, lab.data(), nc, 0, &out, &added, &longest, &err),
            DACPO_OK)
      << err.msg;
  EXPECT_EQ(added, 1u);
  EXPECT_DOUBLE_EQ(longest, 4.0);
  EXPECT_EQ(lab, (std::vector<int32_t>{0, 0, 0}));
  dacpo_adjacency_free(&out);
}
