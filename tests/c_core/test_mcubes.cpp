// SPDX-License-Identifier: BSD-3-Clause
// Marching cubes on cell-centred grids (stage 3, dacpo_mcubes.c): watertight,
// indexed, consistently wound towards higher values, on analytic and random fields.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

extern "C" {
#include "dacpo_mcubes.h"
#include "mcubes_once.hpp"
}

namespace {

struct Grid {
  dacpo_grid g;
  std::vector<float> v;
  Grid(size_t nx, size_t ny, size_t nz, double cell, double ox, double oy, double oz)
  {
    g.dims[0] = nx, g.dims[1] = ny, g.dims[2] = nz;
    g.origin[0] = ox, g.origin[1] = oy, g.origin[2] = oz;
    g.cell = cell;
    v.assign(nx * ny * nz, 0.0f);
  }
  void
  centre(size_t i, size_t j, size_t k, double p[3]) const
  {
    p[0] = g.origin[0] + (i + 0.5) * g.cell;
    p[1] = g.origin[1] + (j + 0.5) * g.cell;
    p[2] = g.origin[2] + (k + 0.5) * g.cell;
  }
  template <class F>
  void
  fill(F f)
  {
    for (size_t k = 0; k < g.dims[2]; ++k)
      for (size_t j = 0; j < g.dims[1]; ++j)
        for (size_t i = 0; i < g.dims[0]; ++i) {
          double p[3];
          centre(i, j, k, p);
          v[i + g.dims[0] * (j + g.dims[1] * k)] = (float)f(p);
        }
  }
};

struct MeshHolder {
  dacpo_mesh m{};
  ~MeshHolder() { dacpo_mesh_free(&m); }
};

void
face_normal(const dacpo_mesh& m, size_t f, double n[3], double c[3])
{
  const int32_t* t = m.triangles + 3 * f;
  const double* a = m.vertices + 3 * t[0];
  const double* b = m.vertices + 3 * t[1];
  const double* d = m.vertices + 3 * t[2];
  double e1[3], e2[3];
  for (int k = 0; k < 3; ++k) {
    e1[k] = b[k] - a[k];
    e2[k] = d[k] - a[k];
    c[k] = (a[k] + b[k] + d[k]) / 3.0;
  }
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

// Directed-edge census: a consistently oriented manifold has every directed
// edge at most once, and its reverse present unless the edge is on the rim.
struct EdgeCensus {
  size_t duplicated = 0; // a directed edge used twice (orientation clash)
  size_t unpaired = 0;   // a directed edge whose reverse is missing (rim)
  size_t edges = 0;      // undirected edges
};

EdgeCensus
census(const dacpo_mesh& m)
{
  std::map<std::pair<int32_t, int32_t>, int> directed;
  for (size_t f = 0; f < m.num_triangles; ++f)
    for (int c = 0; c < 3; ++c)
      directed[{m.triangles[3 * f + c], m.triangles[3 * f + (c + 1) % 3]}]++;
  EdgeCensus e;
  for (const auto& kv : directed) {
    if (kv.second > 1)
      e.duplicated++;
    auto rev = directed.find({kv.first.second, kv.first.first});
    if (rev == directed.end())
      e.unpaired++, e.edges++;
    else if (kv.first.first < kv.first.second)
      e.edges++;
  }
  return e;
}

} // namespace

TEST(DacpoMcubes, SphereIsClosedAccurateAndWoundOutward)
{
  Grid g(24, 24, 24, 0.1, -1.2, -1.2, -1.2);
  const double R = 0.83;
  g.fill([](const double* p) {
    return std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  });
  MeshHolder h;
  dacpo_err err{};
  ASSERT_EQ(mcubes_once(&g.g, g.v.data(), nullptr, R, &h.m, &err), DACPO_OK) << err.msg;
  ASSERT_GT(h.m.num_triangles, 500u);
  // Indexed and watertight: V - E + F = 2 for a sphere, no rim, no clashes.
  EdgeCensus e = census(h.m);
  EXPECT_EQ(e.duplicated, 0u);
  EXPECT_EQ(e.unpaired, 0u);
  EXPECT_EQ((long)h.m.num_vertices - (long)e.edges + (long)h.m.num_triangles, 2);
  // Vertices on the sphere (linear interpolation of |p| is accurate to ~h^2/R).
  for (size_t v = 0; v < h.m.num_vertices; ++v) {
    const double* p = h.m.vertices + 3 * v;
    EXPECT_NEAR(std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), R, 0.01);
  }
  // Every face points towards higher values: outward.
  size_t inward = 0;
  for (size_t f = 0; f < h.m.num_triangles; ++f) {
    double n[3], c[3];
    face_normal(h.m, f, n, c);
    if (n[0] * c[0] + n[1] * c[1] + n[2] * c[2] <= 0.0)
      ++inward;
  }
  EXPECT_EQ(inward, 0u);
}

TEST(DacpoMcubes, PlaneFaceNormalsPointToHigherValues)
{
  Grid g(10, 9, 8, 0.5, 0.0, 0.0, 0.0);
  g.fill([](const double* p) { return 2.0 - p[2]; }); // high below z = 2 - iso
  MeshHolder h;
  dacpo_err err{};
  ASSERT_EQ(mcubes_once(&g.g, g.v.data(), nullptr, 0.3, &h.m, &err), DACPO_OK);
  ASSERT_GT(h.m.num_triangles, 0u);
  for (size_t f = 0; f < h.m.num_triangles; ++f) {
    double n[3], c[3];
    face_normal(h.m, f, n, c);
    EXPECT_LT(n[2], 0.0);
    EXPECT_NEAR(c[2], 1.7, 1e-5);
  }
  // Rim only on the outermost cell centres.
  EdgeCensus e = census(h.m);
  EXPECT_EQ(e.duplicated, 0u);
  EXPECT_EQ(e.unpaired, 2u * (10 - 1) + 2u * (9 - 1)); // perimeter of a 9 x 8 quad grid
}

// Random fields exercise every cube case, the ambiguous faces included: the
// surface must stay a consistently oriented manifold whose rim lies on the
// grid's outer layer.
TEST(DacpoMcubes, RandomFieldsGiveConsistentManifolds)
{
  std::mt19937 rng(12345);
  std::uniform_real_distribution<float> U(-1.0f, 1.0f);
  dacpo_mcubes* mc = nullptr;
  dacpo_err err{};
  ASSERT_EQ(dacpo_mcubes_create(&mc, &err), DACPO_OK);
  for (int trial = 0; trial < 20; ++trial) {
    Grid g(9, 8, 7, 1.0, 0.0, 0.0, 0.0);
    for (float& x : g.v)
      x = U(rng);
    const dacpo_mesh* m = nullptr;
    ASSERT_EQ(dacpo_mcubes_extract(mc, &g.g, g.v.data(), nullptr, 0.05, &m, &err),
              DACPO_OK);
    ASSERT_GT(m->num_triangles, 100u);
    EdgeCensus e = census(*m);
    EXPECT_EQ(e.duplicated, 0u) << "trial " << trial;
    // Rim edges: both end vertices on the outer layer of cell centres.
    std::map<std::pair<int32_t, int32_t>, int> directed;
    for (size_t f = 0; f < m->num_triangles; ++f)
      for (int c = 0; c < 3; ++c)
        directed[{m->triangles[3 * f + c], m->triangles[3 * f + (c + 1) % 3]}]++;
    auto on_outer = [&](int32_t v) {
      const double* p = m->vertices + 3 * v;
      for (int a = 0; a < 3; ++a) {
        double u = p[a] - g.g.origin[a];
        if (std::fabs(u - 0.5) < 1e-6 || std::fabs(u - (g.g.dims[a] - 0.5)) < 1e-6)
          return true;
      }
      return false;
    };
    for (const auto& kv : directed)
      if (!directed.count({kv.first.second, kv.first.first})) {
        EXPECT_TRUE(on_outer(kv.first.first) && on_outer(kv.first.second))
            << "trial " << trial;
      }
    // Every vertex is used, and every vertex lies on a grid edge.
    std::vector<char> used(m->num_vertices, 0);
    for (size_t t = 0; t < 3 * m->num_triangles; ++t)
      used[m->triangles[t]] = 1;
    for (size_t v = 0; v < m->num_vertices; ++v)
      EXPECT_TRUE(used[v]);
  }
  dacpo_mcubes_free(mc);
}

// One vertex per crossed grid edge: the mesh is indexed, not a triangle soup.
TEST(DacpoMcubes, OneVertexPerCrossedEdge)
{
  Grid g(12, 11, 10, 0.2, -1.0, -1.0, -1.0);
  g.fill(
      [](const double* p) { return std::sin(3 * p[0]) + std::cos(2 * p[1]) * p[2]; });
  size_t crossed = 0;
  const size_t nx = 12, ny = 11, nz = 10;
  for (size_t k = 0; k < nz; ++k)
    for (size_t j = 0; j < ny; ++j)
      for (size_t i = 0; i < nx; ++i) {
        const size_t idx = i + nx * (j + ny * k);
        const bool hi = g.v[idx] > 0.1f;
        if (i + 1 < nx && (g.v[idx + 1] > 0.1f) != hi)
          ++crossed;
        if (j + 1 < ny && (g.v[idx + nx] > 0.1f) != hi)
          ++crossed;
        if (k + 1 < nz && (g.v[idx + nx * ny] > 0.1f) != hi)
          ++crossed;
      }
  MeshHolder h;
  dacpo_err err{};
  ASSERT_EQ(mcubes_once(&g.g, g.v.data(), nullptr, 0.1, &h.m, &err), DACPO_OK);
  // One vertex per crossed edge, plus a centroid for the rare loop through
  // both segments of an ambiguous face; no two vertices coincide.
  EXPECT_GE(h.m.num_vertices, crossed);
  EXPECT_LE(h.m.num_vertices, crossed + crossed / 50);
  std::map<std::tuple<double, double, double>, int> pos;
  for (size_t v = 0; v < h.m.num_vertices; ++v)
    pos[{h.m.vertices[3 * v], h.m.vertices[3 * v + 1], h.m.vertices[3 * v + 2]}]++;
  EXPECT_EQ(pos.size(), h.m.num_vertices);
  EXPECT_EQ(census(h.m).duplicated, 0u);
}

TEST(DacpoMcubes, EmptyAndDegenerateInputs)
{
  dacpo_err err{};
  Grid g(5, 5, 5, 1.0, 0, 0, 0);
  g.fill([](const double*) { return 1.0; });
  MeshHolder h;
  ASSERT_EQ(mcubes_once(&g.g, g.v.data(), nullptr, 0.5, &h.m, &err), DACPO_OK);
  EXPECT_EQ(h.m.num_triangles, 0u);
  Grid flat(5, 5, 1, 1.0, 0, 0, 0); // a single layer has no cubes
  MeshHolder h2;
  ASSERT_EQ(mcubes_once(&flat.g, flat.v.data(), nullptr, 0.5, &h2.m, &err), DACPO_OK);
  EXPECT_EQ(h2.m.num_triangles, 0u);
  EXPECT_EQ(mcubes_once(nullptr, g.v.data(), nullptr, 0.5, &h.m, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  dacpo_mcubes* mc = nullptr;
  ASSERT_EQ(dacpo_mcubes_create(&mc, &err), DACPO_OK);
  const dacpo_mesh* m = nullptr;
  EXPECT_EQ(dacpo_mcubes_extract(mc, &g.g, nullptr, nullptr, 0.5, &m, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  dacpo_mcubes_free(mc);
  dacpo_mcubes_free(nullptr);
}
