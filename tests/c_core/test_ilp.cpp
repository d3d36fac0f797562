// SPDX-License-Identifier: BSD-3-Clause
// Stage 5: the 0-1 block-flip program (paper Sec. 5.2, Eq. 8) with lp_solve.
// Known answers: brute force over all 2^n flips for small graphs, hand-solved
// chains and odd cycles, a planted grid-like block graph with noisy edges.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

extern "C" {
#include "dacpo_ilp.h"
}

namespace {

using Edges = std::vector<dacpo_ilp_edge>;

dacpo_ilp_edge
E(int32_t a, int32_t b, double w_same, double w_diff)
{
  dacpo_ilp_edge e;
  e.a = a;
  e.b = b;
  e.w_same = w_same;
  e.w_diff = w_diff;
  return e;
}

double
Objective(const Edges& edges, const std::vector<uint8_t>& o)
{
  double s = 0.0;
  for (const auto& e : edges)
    s += o[e.a] == o[e.b] ? e.w_same : e.w_diff;
  return s;
}

// Maximum of Eq. 8 over all 2^n flips (node 0 fixed: the objective is
// invariant under flipping everything).
double
BruteForce(size_t n, const Edges& edges)
{
  double best = -INFINITY;
  std::vector<uint8_t> o(n, 0);
  const uint64_t count = n == 0 ? 1 : (uint64_t)1 << (n - 1);
  for (uint64_t mask = 0; mask < count; ++mask) {
    for (size_t i = 1; i < n; ++i)
      o[i] = (uint8_t)((mask >> (i - 1)) & 1u);
    best = std::max(best, Objective(edges, o));
  }
  return best;
}

// Lowest node of every connected component of the edge graph (isolated
// nodes are their own component).
std::vector<int32_t>
LowestOfComponent(size_t n, const Edges& edges)
{
  std::vector<int32_t> parent(n);
  for (size_t i = 0; i < n; ++i)
    parent[i] = (int32_t)i;
  auto find = [&](int32_t v) {
    while (parent[v] != v)
      v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& e : edges) {
    int32_t a = find(e.a), b = find(e.b);
    if (a != b)
      parent[std::max(a, b)] = std::min(a, b);
  }
  std::vector<int32_t> low(n);
  for (size_t i = 0; i < n; ++i)
    low[i] = find((int32_t)i); // union by min index: the root is the lowest node
  return low;
}

struct Solved {
  dacpo_status status;
  std::vector<uint8_t> flips;
  dacpo_ilp_result result;
  dacpo_err err;
};

Solved
Solve(size_t n,
      const Edges& edges,
      double time_limit = 30.0,
      const dacpo_progress* progress = nullptr)
{
  Solved s;
  s.flips.assign(n, 7); // sentinel: must be overwritten with 0/1
  std::memset(&s.result, 0, sizeof(s.result));
  std::memset(&s.err, 0, sizeof(s.err));
  s.status = dacpo_ilp_solve(n,
                             edges.size(),
                             edges.empty() ? nullptr : edges.data(),
                             time_limit,
                             progress,
                             n ? s.flips.data() : nullptr,
                             &s.result,
                             &s.err);
  return s;
}

// Checks what every successful answer must satisfy.
void
ExpectValidAnswer(size_t n, const Edges& edges, const Solved& s)
{
  ASSERT_EQ(s.status, DACPO_OK) << s.err.msg;
  std::vector<int32_t> low = LowestOfComponent(n, edges);
  for (size_t i = 0; i < n; ++i) {
    ASSERT_LE(s.flips[i], 1) << "node " << i;
    if (low[i] == (int32_t)i) {
      EXPECT_EQ(s.flips[i], 0)
          << "lowest node " << i << " of its component must be fixed to 0";
    }
  }
  EXPECT_NEAR(
      s.result.objective, Objective(edges, s.flips), 1e-9 * (1.0 + edges.size()));
}

// Small deterministic generator (splitmix64), independent of the library RNG.
struct Rng {
  uint64_t s;
  explicit Rng(uint64_t seed)
      : s(seed)
  {}
  uint64_t
  Next()
  {
    uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double
  Uniform()
  {
    return (double)(Next() >> 11) * (1.0 / 9007199254740992.0);
  }
  size_t
  Below(size_t n)
  {
    return (size_t)(Next() % n);
  }
};

// A W x H grid of blocks, a diagonal in a share of the cells (3-cycles, as in
// a surface segmentation), planted flips, confidences in [0.55, 1], a share of
// noisy edges whose preference is reversed.
Edges
PlantedGrid(size_t w,
            size_t h,
            double p_diag,
            double noise,
            uint64_t seed,
            std::vector<uint8_t>* planted)
{
  Rng rng(seed);
  size_t n = w * h;
  planted->resize(n);
  for (size_t i = 0; i < n; ++i)
    (*planted)[i] = (uint8_t)(rng.Next() >> 63);
  Edges edges;
  auto add = [&](size_t a, size_t b) {
    double conf = 0.55 + 0.45 * rng.Uniform();
    bool same = (*planted)[a] == (*planted)[b];
    if (rng.Uniform() < noise)
      same = !same;
    edges.push_back(
        E((int32_t)a, (int32_t)b, same ? conf : 1.0 - conf, same ? 1.0 - conf : conf));
  };
  for (size_t y = 0; y < h; ++y)
    for (size_t x = 0; x < w; ++x) {
      size_t v = y * w + x;
      if (x + 1 < w)
        add(v, v + 1);
      if (y + 1 < h)
        add(v, v + w);
      if (x + 1 < w && y + 1 < h && rng.Uniform() < p_diag) {
        if (rng.Next() >> 63)
          add(v, v + w + 1);
        else
          add(v + 1, v + w);
      }
    }
  return edges;
}

// A random frustrated graph (spin-glass weights): hard for the 0-1 program.
Edges
HardGraph(size_t n, size_t m, uint64_t seed)
{
  Rng rng(seed);
  Edges edges;
  for (size_t i = 0; i < m; ++i)
    edges.push_back(
        E((int32_t)rng.Below(n), (int32_t)rng.Below(n), rng.Uniform(), rng.Uniform()));
  return edges;
}

} // namespace

TEST(DacpoIlp, EmptyGraph)
{
  Solved s = Solve(0, {});
  ASSERT_EQ(s.status, DACPO_OK) << s.err.msg;
  EXPECT_EQ(s.result.objective, 0.0);
  EXPECT_EQ(s.result.optimal, 1);
  EXPECT_EQ(s.result.constraints, 0u);
}

TEST(DacpoIlp, IsolatedNodesAreNotFlipped)
{
  Solved s = Solve(5, {});
  ExpectValidAnswer(5, {}, s);
  for (uint8_t f : s.flips)
    EXPECT_EQ(f, 0);
  EXPECT_EQ(s.result.optimal, 1);
  EXPECT_EQ(s.result.constraints, 0u);
}

TEST(DacpoIlp, ChainFollowsEveryPreference)
{
  // 0 -same- 1 -diff- 2 -diff- 3 -same- 4 -diff- 5: a tree, satisfiable exactly.
  Edges edges = {E(0, 1, 0.9, 0.1),
                 E(1, 2, 0.2, 0.8),
                 E(2, 3, 0.3, 0.7),
                 E(3, 4, 0.6, 0.4),
                 E(4, 5, 0.05, 0.95)};
  Solved s = Solve(6, edges);
  ExpectValidAnswer(6, edges, s);
  std::vector<uint8_t> expect = {0, 0, 1, 0, 0, 1};
  EXPECT_EQ(s.flips, expect);
  EXPECT_NEAR(s.result.objective, 0.9 + 0.8 + 0.7 + 0.6 + 0.95, 1e-12);
  EXPECT_EQ(s.result.optimal, 1);
  EXPECT_EQ(s.result.constraints, 0u) << "a tree needs no lp_solve";
}

TEST(DacpoIlp, TwoNodeComponent)
{
  Edges edges = {E(3, 1, 0.25, 0.75)};
  Solved s = Solve(4, edges);
  ExpectValidAnswer(4, edges, s);
  std::vector<uint8_t> expect = {0, 0, 0, 1};
  EXPECT_EQ(s.flips, expect);
  EXPECT_DOUBLE_EQ(s.result.objective, 0.75);
  EXPECT_EQ(s.result.optimal, 1);
}

TEST(DacpoIlp, OddCyclesAllPreferringDifferent)
{
  // A cycle of odd length k where every edge wants "different": at most k - 1
  // edges can be cut, so the optimum is k - 1 (one edge stays "same", worth 0).
  for (int k : {3, 5, 7}) {
    Edges edges;
    for (int i = 0; i < k; ++i)
      edges.push_back(E(i, (i + 1) % k, 0.0, 1.0));
    Solved s = Solve((size_t)k, edges);
    ExpectValidAnswer((size_t)k, edges, s);
    EXPECT_NEAR(s.result.objective, k - 1.0, 1e-12) << "cycle " << k;
    EXPECT_EQ(s.result.optimal, 1);
  }
}

TEST(DacpoIlp, CompleteGraphK4UsesTheLpWithTriangleRows)
{
  // K4 with every edge preferring "different": a 2-2 split cuts 4 of 6 edges.
  // The incumbent cannot reach the trivial bound (6), so lp_solve runs on
  // 6 edges x 4 XOR rows + 4 triangles x 4 rows = 40 rows; for K4 the triangle
  // inequalities describe the cut polytope, so no further cut is needed.
  Edges edges;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      edges.push_back(E(a, b, 0.0, 1.0));
  Solved s = Solve(4, edges);
  ExpectValidAnswer(4, edges, s);
  EXPECT_NEAR(s.result.objective, 4.0, 1e-12);
  EXPECT_EQ(s.result.optimal, 1);
  EXPECT_EQ(s.result.constraints, 40u);
  EXPECT_EQ(s.result.cuts_added, 0u);
  int ones = s.flips[0] + s.flips[1] + s.flips[2] + s.flips[3];
  EXPECT_EQ(ones, 2);
}

TEST(DacpoIlp, CompleteGraphsMatchBruteForce)
{
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    Rng rng(seed);
    size_t n = 5 + seed % 5;
    Edges edges;
    for (size_t a = 0; a < n; ++a)
      for (size_t b = a + 1; b < n; ++b)
        edges.push_back(E((int32_t)a, (int32_t)b, rng.Uniform(), rng.Uniform()));
    Solved s = Solve(n, edges);
    ExpectValidAnswer(n, edges, s);
    EXPECT_NEAR(s.result.objective, BruteForce(n, edges), 1e-9) << "seed " << seed;
    EXPECT_EQ(s.result.optimal, 1);
  }
}

TEST(DacpoIlp, RandomGraphsMatchBruteForce)
{
  // Random sparse and dense graphs up to 14 nodes with random weights, also
  // parallel edges, self loops and several components.
  size_t used_lp = 0, cut_instances = 0;
  for (uint64_t seed = 100; seed < 300; ++seed) {
    Rng rng(seed);
    size_t n = 3 + rng.Below(12); // 3..14
    size_t m = rng.Below(3 * n) + 1;
    Edges edges;
    for (size_t i = 0; i < m; ++i) {
      int32_t a = (int32_t)rng.Below(n), b = (int32_t)rng.Below(n);
      double scale = seed % 7 == 0 ? 250.0 : 1.0; // unnormalized weights too
      edges.push_back(E(a, b, scale * rng.Uniform(), scale * rng.Uniform()));
    }
    Solved s = Solve(n, edges);
    ExpectValidAnswer(n, edges, s);
    double bf = BruteForce(n, edges);
    EXPECT_NEAR(s.result.objective, bf, 1e-9 * (1.0 + std::fabs(bf)))
        << "seed " << seed;
    EXPECT_EQ(s.result.optimal, 1) << "seed " << seed;
    used_lp += s.result.constraints > 0;
    cut_instances += s.result.cuts_added > 0;
  }
  // The lp_solve path must have been exercised, not only the heuristic.
  EXPECT_GT(used_lp, 50u);
  (void)cut_instances;
}

TEST(DacpoIlp, PlantedGridRecoversPlantedFlips)
{
  // 10 x 20 blocks with diagonals, 5 % noisy edges: the optimum is at least as
  // good as the planted flips and agrees with them on almost every block.
  std::vector<uint8_t> planted;
  Edges edges = PlantedGrid(10, 20, 0.7, 0.05, 42, &planted);
  Solved s = Solve(200, edges);
  ExpectValidAnswer(200, edges, s);
  EXPECT_EQ(s.result.optimal, 1);
  EXPECT_GE(s.result.objective, Objective(edges, planted) - 1e-9);
  size_t agree = 0;
  for (size_t i = 0; i < 200; ++i)
    agree += (s.flips[i] ^ s.flips[0]) == (planted[i] ^ planted[0]);
  EXPECT_GE(agree, 190u);
  EXPECT_GT(s.result.constraints, 4 * edges.size()) << "triangle rows were added";
  EXPECT_LT(s.result.seconds, 10.0);
}

TEST(DacpoIlp, DisconnectedComponentsAreSolvedSeparately)
{
  // Component A = {1, 3, 5, 7, 9} (frustrated 5-cycle), component B =
  // {2, 4, 6, 8} (K4, all "different"), nodes 0 and 10 isolated.
  Edges edges = {E(3, 1, 0.1, 0.9),
                 E(3, 5, 0.2, 0.8),
                 E(5, 7, 0.1, 0.9),
                 E(7, 9, 0.3, 0.7),
                 E(9, 1, 0.05, 0.95)};
  for (int a : {2, 4, 6, 8})
    for (int b : {2, 4, 6, 8})
      if (a < b)
        edges.push_back(E(a, b, 0.1, 0.6));
  Solved s = Solve(11, edges);
  ExpectValidAnswer(11, edges, s);
  EXPECT_EQ(s.flips[0], 0);
  EXPECT_EQ(s.flips[10], 0);
  EXPECT_EQ(s.flips[1], 0);
  EXPECT_EQ(s.flips[2], 0);
  EXPECT_NEAR(s.result.objective, BruteForce(11, edges), 1e-12);
  EXPECT_EQ(s.result.optimal, 1);
}

TEST(DacpoIlp, TinyTimeLimitReturnsTheIncumbent)
{
  const size_t n = 200;
  Edges edges = HardGraph(n, 600, 7);
  Solved s = Solve(n, edges, 1e-3);
  ExpectValidAnswer(n, edges, s);
  EXPECT_EQ(s.result.optimal, 0);
  EXPECT_GE(s.result.heuristic_wins, 1u);
  // a local optimum: no single flip improves it
  for (size_t v = 0; v < n; ++v) {
    std::vector<uint8_t> o = s.flips;
    o[v] ^= 1u;
    EXPECT_LE(Objective(edges, o), s.result.objective + 1e-9) << "node " << v;
  }
  EXPECT_LT(s.result.seconds, 1.0);
}

TEST(DacpoIlp, FractionalTimeLimitStopsLpSolve)
{
  // lp_solve's own timeout has whole seconds; the abort hook enforces 0.3 s.
  const size_t n = 200;
  Edges edges = HardGraph(n, 600, 7);
  Solved s = Solve(n, edges, 0.3);
  ExpectValidAnswer(n, edges, s);
  EXPECT_EQ(s.result.optimal, 0);
  EXPECT_LT(s.result.seconds, 0.3 + 0.6);
  Solved tiny = Solve(n, edges, 1e-3);
  EXPECT_GE(s.result.objective, tiny.result.objective - 1e-9);
}

namespace {
struct CancelAfter {
  int calls = 0;
  int cancel_at = 0;
  bool wrong_stage = false;
};

int
CancelAfterFn(void* user, dacpo_stage stage, double fraction)
{
  CancelAfter* c = static_cast<CancelAfter*>(user);
  if (stage != DACPO_STAGE_ILP || !(fraction >= 0.0 && fraction <= 1.0))
    c->wrong_stage = true;
  return ++c->calls >= c->cancel_at;
}
} // namespace

TEST(DacpoIlp, CancelFromProgressAtStart)
{
  std::vector<uint8_t> planted;
  Edges edges = PlantedGrid(10, 20, 0.7, 0.05, 42, &planted);
  CancelAfter c;
  c.cancel_at = 1;
  dacpo_progress p = {CancelAfterFn, &c};
  Solved s = Solve(200, edges, 30.0, &p);
  EXPECT_EQ(s.status, DACPO_ERR_CANCELLED);
  EXPECT_EQ(s.err.code, DACPO_ERR_CANCELLED);
  EXPECT_FALSE(c.wrong_stage);
  for (uint8_t f : s.flips)
    EXPECT_EQ(f, 7) << "flip_out must stay untouched on cancel";
}

TEST(DacpoIlp, CancelFromProgressInsideLpSolve)
{
  // Calls: 1 at the start, 2 before the component's lp, 3 from lp_solve's
  // abort hook. The hard graph keeps lp_solve busy far longer than that.
  const size_t n = 200;
  Edges edges = HardGraph(n, 600, 7);
  CancelAfter c;
  c.cancel_at = 3;
  dacpo_progress p = {CancelAfterFn, &c};
  Solved s = Solve(n, edges, 60.0, &p);
  EXPECT_EQ(s.status, DACPO_ERR_CANCELLED) << s.err.msg;
  EXPECT_EQ(c.calls, 3);
  EXPECT_FALSE(c.wrong_stage);
  EXPECT_LT(s.result.seconds, 5.0);
  for (uint8_t f : s.flips)
    EXPECT_EQ(f, 7);
}

TEST(DacpoIlp, ProgressThatNeverCancelsChangesNothing)
{
  std::vector<uint8_t> planted;
  Edges edges = PlantedGrid(10, 10, 0.7, 0.05, 5, &planted);
  CancelAfter c;
  c.cancel_at = 1 << 30;
  dacpo_progress p = {CancelAfterFn, &c};
  Solved a = Solve(100, edges, 30.0, &p);
  Solved b = Solve(100, edges);
  ExpectValidAnswer(100, edges, a);
  EXPECT_GE(c.calls, 2);
  EXPECT_FALSE(c.wrong_stage);
  EXPECT_EQ(a.flips, b.flips) << "runs are repeatable";
  EXPECT_EQ(a.result.objective, b.result.objective);
}

TEST(DacpoIlp, RejectsBadArguments)
{
  Edges edges = {E(0, 1, 0.5, 0.5), E(1, 3, 0.1, 0.9)};
  Solved s = Solve(3, edges); // node 3 does not exist
  EXPECT_EQ(s.status, DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(s.err.msg).find("edge 1"), std::string::npos) << s.err.msg;
  for (uint8_t f : s.flips)
    EXPECT_EQ(f, 7);

  Edges neg = {E(-1, 1, 0.5, 0.5)};
  EXPECT_EQ(Solve(3, neg).status, DACPO_ERR_INVALID_ARGUMENT);

  Edges nan = {E(0, 1, NAN, 0.5)};
  EXPECT_EQ(Solve(2, nan).status, DACPO_ERR_INVALID_ARGUMENT);
  Edges inf = {E(0, 1, 0.5, INFINITY)};
  EXPECT_EQ(Solve(2, inf).status, DACPO_ERR_INVALID_ARGUMENT);

  Edges ok = {E(0, 1, 0.5, 0.7)};
  EXPECT_EQ(Solve(2, ok, 0.0).status, DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(Solve(2, ok, NAN).status, DACPO_ERR_INVALID_ARGUMENT);

  uint8_t flips[2];
  dacpo_err err;
  EXPECT_EQ(dacpo_ilp_solve(2, 1, ok.data(), 1.0, nullptr, flips, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  dacpo_ilp_result r;
  EXPECT_EQ(dacpo_ilp_solve(2, 1, ok.data(), 1.0, nullptr, nullptr, &r, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_ilp_solve(2, 1, nullptr, 1.0, nullptr, flips, &r, &err),
            DACPO_ERR_INVALID_ARGUMENT);
}

TEST(DacpoIlp, ParallelEdgesAndSelfLoopsCount)
{
  // Two parallel edges 0-1 add up (same: 0.3 + 0.3 < diff: 0.1 + 0.6); the
  // self loop on 2 always contributes its w_same.
  Edges edges = {
      E(0, 1, 0.3, 0.1), E(1, 0, 0.3, 0.6), E(2, 2, 0.4, 0.9), E(1, 2, 0.8, 0.1)};
  Solved s = Solve(3, edges);
  ExpectValidAnswer(3, edges, s);
  std::vector<uint8_t> expect = {0, 1, 1};
  EXPECT_EQ(s.flips, expect);
  EXPECT_NEAR(s.result.objective, 0.1 + 0.6 + 0.4 + 0.8, 1e-12);
}
