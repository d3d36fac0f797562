// SPDX-License-Identifier: BSD-3-Clause
// Stage 4a: block adjacency graph and the dipole-boundary edge weight, on
// hand-built grids (the cloud, adjacency and blocks structs are filled here,
// with arrays owned by the test).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

extern "C" {
#include "dacpo_block_graph.h"
#include "dacpo_ilp.h"
}

namespace {

// side x side unit grid in the z = 0 plane with normals +z, split into
// tiles x tiles square blocks (default 2 x 2 quadrants). Tile q = tx + tiles * ty
// gets block id block_id[q] (NULL: q). diagonal: 8-neighbour adjacency
// instead of 4-neighbour.
struct GridScene {
  size_t side;
  std::vector<double> xyz, nrm;
  std::vector<int32_t> block_of;
  std::vector<size_t> start;
  std::vector<int32_t> nbr;
  dacpo_cloud cloud{};
  dacpo_adjacency adj{};
  dacpo_blocks blocks{};

  GridScene(size_t s, bool diagonal, const int32_t* block_id, size_t tiles = 2)
      : side(s)
  {
    const size_t n = side * side;
    for (size_t y = 0; y < side; ++y)
      for (size_t x = 0; x < side; ++x) {
        xyz.insert(xyz.end(), {(double)x, (double)y, 0.0});
        nrm.insert(nrm.end(), {0.0, 0.0, 1.0});
        const size_t q = x * tiles / side + tiles * (y * tiles / side);
        block_of.push_back(block_id ? block_id[q] : (int32_t)q);
      }
    start.push_back(0);
    for (size_t y = 0; y < side; ++y)
      for (size_t x = 0; x < side; ++x) {
        std::vector<int32_t> row;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            if ((dx == 0 && dy == 0) || (!diagonal && dx != 0 && dy != 0))
              continue;
            const long xx = (long)x + dx, yy = (long)y + dy;
            if (xx < 0 || yy < 0 || xx >= (long)side || yy >= (long)side)
              continue;
            row.push_back((int32_t)(yy * (long)side + xx));
          }
        std::sort(row.begin(), row.end());
        nbr.insert(nbr.end(), row.begin(), row.end());
        start.push_back(nbr.size());
      }
    cloud.n = n;
    cloud.input_count = n;
    cloud.xyz = xyz.data();
    cloud.nrm = nrm.data();
    adj.n = n;
    adj.start = start.data();
    adj.nbr = nbr.data();
    blocks.num_blocks = tiles * tiles;
    blocks.block_of = block_of.data();
  }
  void
  flip_block(int32_t b)
  {
    for (size_t i = 0; i < cloud.n; ++i)
      if (block_of[i] == b)
        for (int d = 0; d < 3; ++d)
          nrm[3 * i + d] = -nrm[3 * i + d];
  }
};

const int32_t kIdentity[4] = {0, 1, 2, 3};

const dacpo_block_edge*
find_edge(const dacpo_block_graph& g, int32_t a, int32_t b)
{
  const ptrdiff_t e = dacpo_block_graph_find(&g, a, b);
  return e < 0 ? nullptr : &g.edges[e];
}

} // namespace

TEST(DacpoBlockGraph, FourNeighbourGridGivesFourEdges)
{
  GridScene s(20, false, kIdentity);
  dacpo_block_graph g{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_block_graph_build(&s.blocks, &s.adj, &g, &err), DACPO_OK) << err.msg;
  ASSERT_EQ(g.num_edges, 4u);
  const int32_t expect[4][2] = {{0, 1}, {0, 2}, {1, 3}, {2, 3}};
  for (size_t e = 0; e < 4; ++e) {
    EXPECT_EQ(g.edges[e].a, expect[e][0]);
    EXPECT_EQ(g.edges[e].b, expect[e][1]);
    EXPECT_EQ(g.edges[e].crossing, 10u); // one pair per row/column of the seam
  }
  EXPECT_EQ(dacpo_block_graph_find(&g, 3, 0), -1);
  EXPECT_EQ(dacpo_block_graph_find(&g, 3, 1), 2);
  dacpo_block_graph_free(&g);
  EXPECT_EQ(g.edges, nullptr);
  EXPECT_EQ(g.num_edges, 0u);
}

TEST(DacpoBlockGraph, DiagonalAdjacencyAddsCornerEdges)
{
  // Ids permuted so that the edge list must be sorted, not taken in scan order.
  const int32_t ids[4] = {3, 1, 2, 0};
  GridScene s(20, true, ids);
  dacpo_block_graph g{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_block_graph_build(&s.blocks, &s.adj, &g, &err), DACPO_OK) << err.msg;
  ASSERT_EQ(g.num_edges, 6u);
  for (size_t e = 0; e < g.num_edges; ++e) {
    EXPECT_LT(g.edges[e].a, g.edges[e].b);
    if (e > 0) {
      EXPECT_TRUE(
          g.edges[e - 1].a < g.edges[e].a ||
          (g.edges[e - 1].a == g.edges[e].a && g.edges[e - 1].b < g.edges[e].b));
    }
  }
  // Seams: 10 straight + 2 * 9 diagonal pairs; the two corner edges one each.
  // Quadrants (ids): lower-left 3, lower-right 1, upper-left 2, upper-right 0.
  ASSERT_NE(find_edge(g, 3, 1), nullptr);
  EXPECT_EQ(find_edge(g, 3, 1)->crossing, 28u);
  EXPECT_EQ(find_edge(g, 3, 2)->crossing, 28u);
  EXPECT_EQ(find_edge(g, 1, 0)->crossing, 28u);
  EXPECT_EQ(find_edge(g, 2, 0)->crossing, 28u);
  EXPECT_EQ(find_edge(g, 3, 0)->crossing, 1u);
  EXPECT_EQ(find_edge(g, 1, 2)->crossing, 1u);
  dacpo_block_graph_free(&g);
}

TEST(DacpoBlockGraph, DipoleWeightsFavourConsistentBlocks)
{
  GridScene s(20, false, kIdentity);
  dacpo_block_graph g{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_block_graph_build(&s.blocks, &s.adj, &g, &err), DACPO_OK);
  ASSERT_EQ(dacpo_block_graph_dipole_weights(
                &g, &s.cloud, &s.adj, &s.blocks, s.nrm.data(), 4.0, &err),
            DACPO_OK)
      << err.msg;
  for (size_t e = 0; e < g.num_edges; ++e) {
    // Every seam pair is side by side at distance 1: s = 2 * n.m / 1 = 2.
    EXPECT_NEAR(g.edges[e].alpha, 20.0, 1e-12);
    EXPECT_EQ(g.edges[e].alpha_bar, 0.0);
  }

  // Flip block 3: its two edges now say "differ", the others are unchanged.
  s.flip_block(3);
  ASSERT_EQ(dacpo_block_graph_dipole_weights(
                &g, &s.cloud, &s.adj, &s.blocks, s.nrm.data(), 4.0, &err),
            DACPO_OK);
  for (size_t e = 0; e < g.num_edges; ++e) {
    const dacpo_block_edge& ed = g.edges[e];
    double w_same = -1, w_diff = -1;
    dacpo_edge_omega(ed.alpha, ed.alpha_bar, 0.0, &w_same, &w_diff);
    EXPECT_GE(w_same, 0.0);
    EXPECT_LE(w_same, 1.0);
    EXPECT_GE(w_diff, 0.0);
    EXPECT_LE(w_diff, 1.0);
    EXPECT_LE(w_same + w_diff, 1.0);
    if (ed.b == 3) {
      EXPECT_GT(ed.alpha_bar, ed.alpha);
      EXPECT_NEAR(ed.alpha_bar, 20.0, 1e-12);
      EXPECT_GT(w_diff, 0.99);
    }
    else {
      EXPECT_GT(ed.alpha, ed.alpha_bar);
      EXPECT_GT(w_same, 0.99);
    }
  }
  dacpo_block_graph_free(&g);
}

TEST(DacpoBlockGraph, DipoleWeightsOnThinSheetWantOppositeNormals)
{
  // Two stacked 10 x 10 sheets 1 apart, one block each, adjacency = the grid of
  // each sheet plus the vertical pair. True (outward) normals are opposite; with
  // c = 4 the stacked pairs give e = c - 1 > 0, i.e. evidence for the blocks as
  // they are. Flipping one sheet moves all of it to alpha_bar.
  const size_t side = 10, n = 2 * side * side;
  std::vector<double> xyz, nrm;
  std::vector<int32_t> block_of;
  for (int sheet = 0; sheet < 2; ++sheet)
    for (size_t y = 0; y < side; ++y)
      for (size_t x = 0; x < side; ++x) {
        xyz.insert(xyz.end(), {(double)x, (double)y, sheet == 0 ? 0.5 : -0.5});
        nrm.insert(nrm.end(), {0.0, 0.0, sheet == 0 ? 1.0 : -1.0});
        block_of.push_back(sheet);
      }
  std::vector<size_t> start{0};
  std::vector<int32_t> nbr;
  for (size_t i = 0; i < n; ++i) {
    const size_t sheet = i / (side * side), local = i % (side * side);
    const size_t x = local % side, y = local / side;
    std::vector<int32_t> row;
    if (y > 0)
      row.push_back((int32_t)(i - side));
    if (x > 0)
      row.push_back((int32_t)(i - 1));
    if (x + 1 < side)
      row.push_back((int32_t)(i + 1));
    if (y + 1 < side)
      row.push_back((int32_t)(i + side));
    row.push_back((int32_t)(sheet == 0 ? i + side * side : i - side * side));
    std::sort(row.begin(), row.end());
    nbr.insert(nbr.end(), row.begin(), row.end());
    start.push_back(nbr.size());
  }
  dacpo_cloud cloud{};
  cloud.n = n;
  cloud.xyz = xyz.data();
  cloud.nrm = nrm.data();
  dacpo_adjacency adj{n, start.data(), nbr.data()};
  dacpo_blocks blocks{};
  blocks.num_blocks = 2;
  blocks.block_of = block_of.data();

  dacpo_block_graph g{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_block_graph_build(&blocks, &adj, &g, &err), DACPO_OK);
  ASSERT_EQ(g.num_edges, 1u);
  EXPECT_EQ(g.edges[0].crossing, 100u);
  ASSERT_EQ(dacpo_block_graph_dipole_weights(
                &g, &cloud, &adj, &blocks, nrm.data(), 4.0, &err),
            DACPO_OK);
  EXPECT_NEAR(g.edges[0].alpha, 100 * 2.0 * 3.0, 1e-9);
  EXPECT_EQ(g.edges[0].alpha_bar, 0.0);
  for (size_t i = side * side; i < n; ++i)
    nrm[3 * i + 2] = -nrm[3 * i + 2];
  ASSERT_EQ(dacpo_block_graph_dipole_weights(
                &g, &cloud, &adj, &blocks, nrm.data(), 4.0, &err),
            DACPO_OK);
  EXPECT_EQ(g.edges[0].alpha, 0.0);
  EXPECT_NEAR(g.edges[0].alpha_bar, 600.0, 1e-9);
  dacpo_block_graph_free(&g);
}

TEST(DacpoBlockGraph, OmegaOfEq7)
{
  double ws = -1, wd = -1;
  dacpo_edge_omega(3.0, 1.0, 0.0, &ws, &wd); // scale 0: Eq. 7 as printed
  EXPECT_NEAR(ws, 0.75, 1e-12);
  EXPECT_NEAR(wd, 0.25, 1e-12);
  EXPECT_LE(ws + wd, 1.0);
  dacpo_edge_omega(0.0, 0.0, 1.0, &ws, &wd); // no evidence: zero, not NaN
  EXPECT_EQ(ws, 0.0);
  EXPECT_EQ(wd, 0.0);
  dacpo_edge_omega(
      1e-300, 0.0, 0.0, &ws, &wd); // tiny evidence keeps its ratio (no eps)
  EXPECT_NEAR(ws, 1.0, 1e-12);
  dacpo_edge_omega(HUGE_VAL, 1.0, 1.0, &ws, &wd); // not finite: no evidence
  EXPECT_EQ(ws, 0.0);
  EXPECT_EQ(wd, 0.0);
  dacpo_edge_omega(1.0, 2.0, 1.0, nullptr, nullptr); // NULL-safe
}

TEST(DacpoBlockGraph, OmegaKeepsTheAmountOfEvidence)
{
  // Same ratio, 1000x less evidence than a typical edge: same confidence, about
  // 1/1000 of the weight; a typical edge keeps half of Eq. 7's weight, a strong
  // one almost all of it.
  double ws = 0, wd = 0, ts = 0, td = 0, bs = 0, bd = 0;
  dacpo_edge_omega(0.9e-3, 0.1e-3, 1.0, &ws, &wd);
  dacpo_edge_omega(0.9, 0.1, 1.0, &ts, &td);
  dacpo_edge_omega(900.0, 100.0, 1.0, &bs, &bd);
  EXPECT_NEAR(ws / (ws + wd), 0.9, 1e-12);
  EXPECT_NEAR(ws + wd, 1e-3 / (1.0 + 1e-3), 1e-12);
  EXPECT_NEAR(ts + td, 0.5, 1e-12);
  EXPECT_NEAR(bs + bd, 1000.0 / 1001.0, 1e-12);
  EXPECT_GT((ts - td) / (ws - wd), 400.0);
}

TEST(DacpoBlockGraph, EvidenceScaleIsTheMedianOfEdgesWithEvidence)
{
  dacpo_block_edge e[4] = {{0, 1, 1, 1.0, 0.0},
                           {0, 2, 1, 0.0, 0.0},
                           {1, 2, 1, 2.0, 1.0},
                           {2, 3, 1, 5.0, 5.0}};
  dacpo_block_graph g = {4, e};
  EXPECT_DOUBLE_EQ(dacpo_edge_evidence_scale(&g), 3.0); // median of {1, 3, 10}
  g.num_edges = 0;
  EXPECT_EQ(dacpo_edge_evidence_scale(&g), 0.0);
}

// Two measures as one: each in units of its own typical (median) edge, the
// second times the weight. VCR evidence {2, 4, 2} (median 2) and seam energy
// {10, 10, 30} (median 10) at weight 0.5.
TEST(DacpoBlockGraph, BlendAddsTwoMeasuresInUnitsOfTheirTypicalEdge)
{
  dacpo_block_edge v[3] = {{0, 1, 1, 2.0, 0.0}, {0, 2, 1, 1.0, 1.0}, {1, 2, 1, 0.0, 4.0}};
  dacpo_block_edge d[3] = {{0, 1, 1, 0.0, 10.0}, {0, 2, 1, 0.0, 30.0}, {1, 2, 1, 10.0, 0.0}};
  dacpo_block_graph g = {3, v}, o = {3, d};
  dacpo_err err = {DACPO_OK, {0}};
  ASSERT_EQ(dacpo_block_graph_blend(&g, &o, 0.5, &err), DACPO_OK) << err.msg;
  const double want[3][2] = {{1.0, 0.5}, {0.5, 2.0}, {0.5, 2.0}};
  for (int e = 0; e < 3; ++e) {
    EXPECT_DOUBLE_EQ(v[e].alpha, want[e][0]) << e;
    EXPECT_DOUBLE_EQ(v[e].alpha_bar, want[e][1]) << e;
  }
}

TEST(DacpoBlockGraph, BlendWithoutEvidenceOrWeightKeepsTheFirstMeasure)
{
  dacpo_block_edge v[2] = {{0, 1, 1, 3.0, 1.0}, {1, 2, 1, 0.0, 2.0}};
  dacpo_block_edge z[2] = {{0, 1, 1, 0.0, 0.0}, {1, 2, 1, 0.0, 0.0}};
  dacpo_block_graph g = {2, v}, o = {2, z};
  dacpo_err err = {DACPO_OK, {0}};
  ASSERT_EQ(dacpo_block_graph_blend(&g, &o, 1.0, &err), DACPO_OK) << err.msg;
  EXPECT_DOUBLE_EQ(v[0].alpha, 1.0); // median of {4, 2} = 3
  EXPECT_DOUBLE_EQ(v[0].alpha_bar, 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(v[1].alpha_bar, 2.0 / 3.0);
  z[0].alpha = 5.0;
  ASSERT_EQ(dacpo_block_graph_blend(&g, &o, 0.0, &err), DACPO_OK) << err.msg;
  EXPECT_DOUBLE_EQ(v[0].alpha, 1.0); // already in its own units (median 1): as it was
}

TEST(DacpoBlockGraph, BlendRefusesOtherEdgesAndBadWeights)
{
  dacpo_block_edge v[2] = {{0, 1, 1, 1.0, 0.0}, {1, 2, 1, 0.0, 1.0}};
  dacpo_block_edge w[2] = {{0, 1, 1, 1.0, 0.0}, {1, 3, 1, 0.0, 1.0}};
  dacpo_block_graph g = {2, v}, o = {2, w}, one = {1, w};
  dacpo_err err = {DACPO_OK, {0}};
  EXPECT_EQ(dacpo_block_graph_blend(&g, &o, 1.0, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(err.msg).find("edge 1"), std::string::npos) << err.msg;
  EXPECT_EQ(dacpo_block_graph_blend(&g, &one, 1.0, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_block_graph_blend(&g, &g, -1.0, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_block_graph_blend(&g, &g, NAN, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_block_graph_blend(nullptr, &g, 1.0, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_DOUBLE_EQ(v[0].alpha, 1.0); // untouched by the refused calls
}

TEST(DacpoBlockGraph, SingleBlockAndEmptyInputHaveNoEdges)
{
  const int32_t one[4] = {0, 0, 0, 0};
  GridScene s(6, true, one);
  s.blocks.num_blocks = 1;
  dacpo_block_graph g{};
  dacpo_err err{};
  ASSERT_EQ(dacpo_block_graph_build(&s.blocks, &s.adj, &g, &err), DACPO_OK);
  EXPECT_EQ(g.num_edges, 0u);
  EXPECT_EQ(dacpo_block_graph_dipole_weights(
                &g, &s.cloud, &s.adj, &s.blocks, s.nrm.data(), 4.0, &err),
            DACPO_OK);
  dacpo_block_graph_free(&g);

  size_t zero = 0;
  dacpo_adjacency empty{0, &zero, nullptr};
  dacpo_blocks none{};
  ASSERT_EQ(dacpo_block_graph_build(&none, &empty, &g, &err), DACPO_OK);
  EXPECT_EQ(g.num_edges, 0u);
  dacpo_block_graph_free(&g);
  dacpo_block_graph_free(nullptr);
}

TEST(DacpoBlockGraph, RejectsInconsistentInput)
{
  GridScene s(6, false, kIdentity);
  dacpo_block_graph g{};
  dacpo_err err{};
  EXPECT_EQ(dacpo_block_graph_build(nullptr, &s.adj, &g, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_block_graph_build(&s.blocks, &s.adj, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);

  s.block_of[7] = 4; // outside [0, num_blocks)
  EXPECT_EQ(dacpo_block_graph_build(&s.blocks, &s.adj, &g, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(err.msg).find("point 7"), std::string::npos) << err.msg;
  EXPECT_EQ(g.num_edges, 0u);
  s.block_of[7] = 0;

  const int32_t saved = s.nbr[3];
  s.nbr[3] = 1000; // neighbour out of range
  EXPECT_EQ(dacpo_block_graph_build(&s.blocks, &s.adj, &g, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  s.nbr[3] = saved;

  // A graph built for one labelling does not fit another.
  ASSERT_EQ(dacpo_block_graph_build(&s.blocks, &s.adj, &g, &err), DACPO_OK);
  const int32_t other[4] = {0, 3, 1, 2}; // seam lower-left|lower-right = (0, 3)
  GridScene t(6, false, other);
  EXPECT_EQ(dacpo_block_graph_dipole_weights(
                &g, &t.cloud, &t.adj, &t.blocks, t.nrm.data(), 4.0, &err),
            DACPO_ERR_INTERNAL)
      << err.msg;
  EXPECT_EQ(dacpo_block_graph_dipole_weights(
                &g, &s.cloud, &s.adj, &s.blocks, nullptr, 4.0, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_block_graph_dipole_weights(
                &g, &s.cloud, &s.adj, &s.blocks, s.nrm.data(), NAN, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  dacpo_block_graph_free(&g);
}

TEST(DacpoBlockGraph, TinyContactCannotOutvoteALongSharedBoundary)
{
  // A ring of 6 blocks: five long shared boundaries (evidence ~1) all say
  // "same", one tiny contact (evidence 1e-4, i.e. a few pixels) says "differ"
  // with full confidence. Under Eq. 7 as printed every edge weighs 1 and the
  // 0-1 program must break a strong edge as often as the tiny one (a tie); with
  // the amount of evidence kept, only the tiny contact is overruled.
  std::vector<dacpo_block_edge> e;
  for (int32_t b = 0; b + 1 < 6; ++b)
    e.push_back({b, b + 1, 100, 0.9 + 0.05 * b, 0.01});
  e.push_back({0, 5, 1, 0.0, 1e-4});
  dacpo_block_graph g = {e.size(), e.data()};
  const double scale = dacpo_edge_evidence_scale(&g);
  std::vector<dacpo_ilp_edge> ie;
  for (const dacpo_block_edge& be : e) {
    dacpo_ilp_edge x = {be.a, be.b, 0, 0};
    dacpo_edge_omega(be.alpha, be.alpha_bar, scale, &x.w_same, &x.w_diff);
    ie.push_back(x);
  }
  uint8_t flips[6];
  dacpo_ilp_result r;
  dacpo_err err = {DACPO_OK, {0}};
  ASSERT_EQ(dacpo_ilp_solve(6, ie.size(), ie.data(), 5.0, nullptr, flips, &r, &err),
            DACPO_OK)
      << err.msg;
  for (int b = 1; b < 6; ++b)
    EXPECT_EQ(flips[b], flips[0]) << "block " << b;
  // The same edges under Eq. 7 as printed: breaking the tiny contact is no
  // better than breaking a long boundary.
  double ts, td, ls, ld;
  dacpo_edge_omega(0.0, 1e-4, 0.0, &ts, &td);
  dacpo_edge_omega(0.9, 0.01, 0.0, &ls, &ld);
  EXPECT_GT(td - ts, 0.99 * (ls - ld));
}

// Blocks wrong inside: a 60 x 60 grid in 5 x 5 blocks of 12 x 12 points, every
// block with a share of its points turned over at random (as stage 2 leaves
// noisy parts), and a planted pattern of whole blocks turned over. The seam
// evidence (dipole-boundary weights), Eq. 7 with the evidence scale and the 0-1
// program must recover every planted flip. Shares up to 25 % are recovered
// (a seam's pairs then agree 62.5 : 37.5); at 30 % (58 : 42) a group of 10-23
// blocks comes out turned over, so that is not asserted. Scattered errors only:
// a block whose wrong part lies along its seams cannot be recovered from them.
TEST(DacpoBlockGraph, BlocksWrongInsideStillGetEveryFlipRight)
{
  for (const double wrong : {0.0, 0.2, 0.25}) {
    SCOPED_TRACE(wrong);
    GridScene s(60, true, nullptr, 5);
    const size_t nb = s.blocks.num_blocks;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::vector<uint8_t> planted(nb);
    for (auto& f : planted)
      f = uniform(rng) < 0.5;
    size_t turned = 0;
    for (size_t i = 0; i < s.cloud.n; ++i) {
      const bool inside = uniform(rng) < wrong;
      turned += inside;
      if ((planted[s.block_of[i]] != 0) != inside)
        for (int d = 0; d < 3; ++d)
          s.nrm[3 * i + d] = -s.nrm[3 * i + d];
    }
    EXPECT_NEAR(double(turned) / double(s.cloud.n), wrong, 0.02);

    dacpo_block_graph g{};
    dacpo_err err{};
    ASSERT_EQ(dacpo_block_graph_build(&s.blocks, &s.adj, &g, &err), DACPO_OK);
    ASSERT_EQ(dacpo_block_graph_dipole_weights(
                  &g, &s.cloud, &s.adj, &s.blocks, s.nrm.data(), 1.5, &err),
              DACPO_OK)
        << err.msg;
    const double scale = dacpo_edge_evidence_scale(&g);
    std::vector<dacpo_ilp_edge> ie(g.num_edges);
    for (size_t e = 0; e < g.num_edges; ++e) {
      ie[e].a = g.edges[e].a;
      ie[e].b = g.edges[e].b;
      dacpo_edge_omega(
          g.edges[e].alpha, g.edges[e].alpha_bar, scale, &ie[e].w_same, &ie[e].w_diff);
    }
    std::vector<uint8_t> flips(nb);
    dacpo_ilp_result res{};
    ASSERT_EQ(dacpo_ilp_solve(
                  nb, ie.size(), ie.data(), 30.0, nullptr, flips.data(), &res, &err),
              DACPO_OK)
        << err.msg;
    for (size_t b = 0; b < nb; ++b)
      EXPECT_EQ(flips[b] ^ flips[0], planted[b] ^ planted[0]) << "block " << b;
    dacpo_block_graph_free(&g);
  }
}
