// SPDX-License-Identifier: BSD-3-Clause
// Stage 3's face queries from per-cell candidate lists: the same answer as the
// kd-tree, bit for bit (indices, order, squared distances), whichever path
// answers; and the lists answer most queries near a sampled surface.
extern "C" {
#include "dacpo_cell_knn.h"
#include "dacpo_kdtree.h"
}

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace {

struct Fixture {
  std::vector<double> xyz;
  dacpo_kdtree* tree = nullptr;
  dacpo_grid grid{};

  // A grid over [-1, 1]^3 (plus a margin) with cells of `cell`.
  explicit Fixture(std::vector<double> pts, double cell)
      : xyz(std::move(pts))
  {
    dacpo_err err{};
    EXPECT_EQ(dacpo_kdtree_build(xyz.data(), xyz.size() / 3, &tree, &err), DACPO_OK);
    grid.cell = cell;
    for (int a = 0; a < 3; ++a) {
      grid.origin[a] = -1.1;
      grid.dims[a] = static_cast<size_t>(std::ceil(2.2 / cell));
    }
  }
  ~Fixture() { dacpo_kdtree_free(tree); }
};

// A wavy sheet z = 0.1 sin(3x) sampled at random with about `n` points, noisy.
std::vector<double>
wavySheet(size_t n, double noise, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> g(0.0, noise);
  std::vector<double> xyz;
  for (size_t i = 0; i < n; ++i) {
    double x = u(rng), y = u(rng);
    xyz.insert(xyz.end(), {x, y, 0.1 * std::sin(3.0 * x) + g(rng)});
  }
  return xyz;
}

// Queries near the sheet (where iPSR's faces are) and anywhere in the box;
// returns the share answered from a list.
double
expectSameAsTree(Fixture& f, size_t k, uint32_t seed)
{
  dacpo_cell_knn* c = nullptr;
  dacpo_err err{};
  EXPECT_EQ(dacpo_cell_knn_create(
                f.tree, f.xyz.data(), f.xyz.size() / 3, &f.grid, k, &c, &err),
            DACPO_OK)
      << err.msg;
  if (!c)
    return 0.0;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.05, 1.05);
  std::normal_distribution<double> g(0.0, 0.02);
  std::vector<int32_t> a(k + 1, -7), b(k + 1, -7);
  std::vector<double> da(k + 1, -7.0), db(k + 1, -7.0);
  for (int i = 0; i < 4000; ++i) {
    double q[3] = {u(rng), u(rng), 0.0};
    q[2] = i % 4 == 3 ? u(rng) : 0.1 * std::sin(3.0 * q[0]) + g(rng);
    size_t want = dacpo_kdtree_knn(f.tree, q, k, a.data(), da.data());
    size_t got = dacpo_cell_knn_query(c, q, b.data(), db.data());
    EXPECT_EQ(got, want) << "query " << i;
    for (size_t j = 0; j < want && j < got; ++j) {
      EXPECT_EQ(b[j], a[j]) << "query " << i << " rank " << j;
      EXPECT_EQ(db[j], da[j]) << "query " << i << " rank " << j;
    }
    EXPECT_EQ(b[k], -7) << "wrote past the answer";
  }
  size_t listed = 0, to_tree = 0;
  dacpo_cell_knn_counts(c, &listed, &to_tree);
  EXPECT_EQ(listed + to_tree, 4000u);
  EXPECT_GT(dacpo_cell_knn_bytes(c), 0u);
  dacpo_cell_knn_free(c);
  return static_cast<double>(listed) / 4000.0;
}

} // namespace

TEST(DacpoCellKnn, SameAnswerAsTheTreeOnASampledSurface)
{
  // 40,000 points on ~4 m^2: spacing about 0.01, cells of one spacing.
  Fixture f(wavySheet(40000, 0.002, 3), 0.01);
  const double listed = expectSameAsTree(f, 10, 11);
  // near the sheet most queries are answered by the lists (3 in 4 queries lie
  // there); the queries far off go to the tree
  EXPECT_GT(listed, 0.6);
}

TEST(DacpoCellKnn, SameAnswerWithCoarseCellsAndLargeK)
{
  // Cells of 5 spacings: the lists rarely reach, the tree answers; k = 64.
  Fixture f(wavySheet(20000, 0.0, 5), 0.07);
  expectSameAsTree(f, 64, 12);
}

TEST(DacpoCellKnn, TiesGoToTheLowerIndexAsInTheTree)
{
  // every point twice, and points on an exact lattice: equal distances abound
  std::vector<double> xyz;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j)
      for (int rep = 0; rep < 2; ++rep)
        xyz.insert(xyz.end(), {-0.9 + 0.06 * i, -0.9 + 0.06 * j, 0.0});
  Fixture f(xyz, 0.06);
  dacpo_cell_knn* c = nullptr;
  dacpo_err err{};
  ASSERT_EQ(
      dacpo_cell_knn_create(f.tree, f.xyz.data(), xyz.size() / 3, &f.grid, 7, &c, &err),
      DACPO_OK);
  int32_t a[7], b[7];
  double da[7], db[7];
  for (int i = 0; i < 29; ++i)
    for (int j = 0; j < 29; ++j) {
      // lattice points, cell corners and midpoints between points
      const double q[3] = {-0.9 + 0.06 * i + 0.03 * (j % 2), -0.9 + 0.06 * j, 0.0};
      size_t want = dacpo_kdtree_knn(f.tree, q, 7, a, da);
      ASSERT_EQ(dacpo_cell_knn_query(c, q, b, db), want);
      for (size_t r = 0; r < want; ++r) {
        ASSERT_EQ(b[r], a[r]) << i << "," << j << " rank " << r;
        ASSERT_EQ(db[r], da[r]);
      }
    }
  dacpo_cell_knn_free(c);
}

TEST(DacpoCellKnn, FewPointsAndQueriesOffTheGrid)
{
  // 5 points, k = 3: a list holds every point (it always answers); queries
  // beyond the grid fall in its border cells; a non-finite query gets none.
  std::vector<double> xyz = {
      0, 0, 0, 0.1, 0, 0, 0, 0.2, 0, 0.5, 0.5, 0.5, -0.3, 0, 0.1};
  Fixture f(xyz, 0.25);
  dacpo_cell_knn* c = nullptr;
  dacpo_err err{};
  ASSERT_EQ(dacpo_cell_knn_create(f.tree, f.xyz.data(), 5, &f.grid, 3, &c, &err),
            DACPO_OK);
  int32_t a[3], b[3];
  double da[3], db[3];
  const double qs[][3] = {{0.01, 0.02, 0}, {5, 5, 5}, {-7, 0, 0.1}, {0.4, 0.4, 0.45}};
  for (const auto& q : qs) {
    size_t want = dacpo_kdtree_knn(f.tree, q, 3, a, da);
    ASSERT_EQ(want, 3u);
    ASSERT_EQ(dacpo_cell_knn_query(c, q, b, db), want);
    for (size_t r = 0; r < want; ++r) {
      EXPECT_EQ(b[r], a[r]);
      EXPECT_EQ(db[r], da[r]);
    }
  }
  const double nan[3] = {std::numeric_limits<double>::quiet_NaN(), 0, 0};
  EXPECT_EQ(dacpo_cell_knn_query(c, nan, b, db), 0u);
  size_t listed = 0, to_tree = 0;
  dacpo_cell_knn_counts(c, &listed, &to_tree);
  EXPECT_EQ(listed, 4u);
  EXPECT_EQ(to_tree, 1u);
  dacpo_cell_knn_free(c);
}

TEST(DacpoCellKnn, BadArgumentsAreRefused)
{
  Fixture f(wavySheet(100, 0.0, 1), 0.1);
  dacpo_cell_knn* c = nullptr;
  dacpo_err err{};
  EXPECT_EQ(dacpo_cell_knn_create(f.tree, f.xyz.data(), 100, &f.grid, 0, &c, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_cell_knn_create(f.tree, f.xyz.data(), 100, &f.grid, 65, &c, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_cell_knn_create(f.tree, f.xyz.data(), 100, nullptr, 10, &c, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  dacpo_grid empty = f.grid;
  empty.dims[1] = 0;
  EXPECT_EQ(dacpo_cell_knn_create(f.tree, f.xyz.data(), 100, &empty, 10, &c, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(c, nullptr);
}
