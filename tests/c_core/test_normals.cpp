// SPDX-License-Identifier: BSD-3-Clause
// PCA normals: known answers on a plane and a sphere, and finite unit vectors
// for degenerate (collinear, coincident, isolated) neighbourhoods.
extern "C" {
#include "dacpo_normals.h"
}

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

namespace {

// A distinct cloud from double coordinates (no float rounding), so a plane
// stays exactly planar up to double precision.
struct DoubleCloud {
  std::vector<double> xyz, nrm;
  std::vector<int32_t> rep, map;
  dacpo_cloud c{};
  explicit DoubleCloud(std::vector<double> p)
      : xyz(std::move(p))
  {
    size_t n = xyz.size() / 3;
    nrm.assign(3 * n, 0.0);
    rep.resize(n);
    for (size_t i = 0; i < n; ++i)
      rep[i] = static_cast<int32_t>(i);
    map = rep;
    c.n = n;
    c.input_count = n;
    c.xyz = xyz.data();
    c.nrm = nrm.data();
    c.rep_input = rep.data();
    c.input_to_point = map.data();
  }
};

struct Graph {
  dacpo_knn_graph g{};
  ~Graph() { dacpo_knn_graph_free(&g); }
};

double
norm3(const double* v)
{
  return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

// |sin| of the angle between two axes (sign-free)
double
axisError(const double* a, const double* b)
{
  double c[3] = {
      a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  return norm3(c) / (norm3(a) * norm3(b));
}

void
expectUnitFinite(const std::vector<double>& nrm, const std::vector<float>& curv)
{
  for (size_t i = 0; i < curv.size(); ++i) {
    ASSERT_TRUE(std::isfinite(nrm[3 * i]) && std::isfinite(nrm[3 * i + 1]) &&
                std::isfinite(nrm[3 * i + 2]))
        << "point " << i;
    EXPECT_NEAR(norm3(&nrm[3 * i]), 1.0, 1e-12) << "point " << i;
    EXPECT_TRUE(std::isfinite(curv[i]));
    EXPECT_GE(curv[i], 0.0f);
    EXPECT_LE(curv[i], 1.0f / 3.0f + 1e-6f);
  }
}

} // namespace

TEST(DacpoNormals, PlaneNormalsAreExact)
{
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const size_t n = 3000;
  std::vector<double> p(3 * n);
  for (size_t i = 0; i < n; ++i) {
    double x = u(rng), y = u(rng);
    p[3 * i] = x;
    p[3 * i + 1] = y;
    p[3 * i + 2] = 0.3 * x - 0.2 * y;
  }
  DoubleCloud dc(p);
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&dc.c, 16, nullptr, 2, nullptr, &g.g, &err), DACPO_OK);
  std::vector<double> nrm(3 * n, NAN);
  std::vector<float> curv(n, -1.0f);
  ASSERT_EQ(dacpo_normals_pca(&dc.c, &g.g, 16, 2, nrm.data(), curv.data(), &err),
            DACPO_OK)
      << err.msg;
  const double truth[3] = {-0.3, 0.2, 1.0};
  expectUnitFinite(nrm, curv);
  for (size_t i = 0; i < n; ++i) {
    ASSERT_LT(axisError(&nrm[3 * i], truth), 1e-6) << "point " << i;
    EXPECT_LT(curv[i], 1e-10f);
  }
}

TEST(DacpoNormals, SphereNormalsAreRadial)
{
  std::mt19937 rng(2);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const size_t n = 4000;
  std::vector<double> p(3 * n);
  for (size_t i = 0; i < n; ++i) {
    double v[3] = {gauss(rng), gauss(rng), gauss(rng)};
    double l = norm3(v);
    for (int d = 0; d < 3; ++d)
      p[3 * i + d] = 2.0 + 5.0 * v[d] / l; // radius 5, centre (2, 2, 2)
  }
  DoubleCloud dc(p);
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&dc.c, 12, nullptr, 1, nullptr, &g.g, &err), DACPO_OK);
  std::vector<double> nrm(3 * n);
  std::vector<float> curv(n);
  ASSERT_EQ(dacpo_normals_pca(&dc.c, &g.g, 12, 1, nrm.data(), curv.data(), &err),
            DACPO_OK);
  expectUnitFinite(nrm, curv);
  double worst = 0.0, mean_curv = 0.0;
  for (size_t i = 0; i < n; ++i) {
    double radial[3] = {p[3 * i] - 2.0, p[3 * i + 1] - 2.0, p[3 * i + 2] - 2.0};
    worst = std::max(worst, axisError(&nrm[3 * i], radial));
    mean_curv += curv[i] / static_cast<double>(n);
  }
  EXPECT_LT(worst, 0.1);      // sin of the angle: under ~6 degrees for every point
  EXPECT_GT(mean_curv, 1e-5); // curved, unlike the plane
  EXPECT_LT(mean_curv, 0.02);
}

TEST(DacpoNormals, RotatedRingWithRepeatedEigenvalues)
{
  // 16 points on a circle plus the centre, in a tilted plane: l1 == l2.
  const double a[3] = {1.0 / std::sqrt(2.0), 0.0, 1.0 / std::sqrt(2.0)};
  const double b[3] = {-0.5, 1.0 / std::sqrt(2.0), 0.5};
  const double truth[3] = {
      a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  std::vector<double> p = {10.0, -3.0, 7.0};
  for (int j = 0; j < 16; ++j) {
    double t = 2.0 * M_PI * j / 16.0;
    for (int d = 0; d < 3; ++d)
      p.push_back(p[d] + 0.01 * (std::cos(t) * a[d] + std::sin(t) * b[d]));
  }
  DoubleCloud dc(p);
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&dc.c, 16, nullptr, 1, nullptr, &g.g, &err), DACPO_OK);
  std::vector<double> nrm(3 * 17);
  std::vector<float> curv(17);
  ASSERT_EQ(dacpo_normals_pca(&dc.c, &g.g, 16, 1, nrm.data(), curv.data(), &err),
            DACPO_OK);
  expectUnitFinite(nrm, curv);
  for (size_t i = 0; i < 17; ++i)
    EXPECT_LT(axisError(&nrm[3 * i], truth), 1e-9) << "point " << i;
}

TEST(DacpoNormals, CollinearNeighbourhoodGivesPerpendicularUnitAxis)
{
  std::vector<double> p;
  const double dir[3] = {2.0 / 3.0, -1.0 / 3.0, 2.0 / 3.0};
  for (int i = 0; i < 20; ++i)
    for (int d = 0; d < 3; ++d)
      p.push_back(1.0 + 0.1 * i * dir[d]);
  DoubleCloud dc(p);
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&dc.c, 6, nullptr, 1, nullptr, &g.g, &err), DACPO_OK);
  std::vector<double> nrm(3 * 20);
  std::vector<float> curv(20);
  ASSERT_EQ(dacpo_normals_pca(&dc.c, &g.g, 6, 1, nrm.data(), curv.data(), &err),
            DACPO_OK);
  expectUnitFinite(nrm, curv);
  for (size_t i = 0; i < 20; ++i) {
    double dot =
        nrm[3 * i] * dir[0] + nrm[3 * i + 1] * dir[1] + nrm[3 * i + 2] * dir[2];
    EXPECT_LT(std::fabs(dot), 1e-9) << "point " << i;
    EXPECT_LT(curv[i], 1e-12f);
  }
}

TEST(DacpoNormals, CoincidentAndIsolatedNeighbourhoodsAreFinite)
{
  // Five identical points (a cloud built by hand, so not merged) whose graph
  // lists each other, and a sixth point with no neighbours at all.
  std::vector<double> p;
  for (int i = 0; i < 5; ++i)
    p.insert(p.end(), {0.5, 0.5, 0.5});
  p.insert(p.end(), {9.0, 9.0, 9.0});
  DoubleCloud dc(p);
  dacpo_knn_graph g{};
  g.n = 6;
  g.k = 4;
  std::vector<int32_t> idx(24, -1);
  std::vector<float> sqd(24, INFINITY);
  for (int i = 0; i < 5; ++i)
    for (int r = 0, j = 0; j < 5; ++j)
      if (j != i) {
        idx[i * 4 + r] = j;
        sqd[i * 4 + r++] = 0.0f;
      }
  g.idx = idx.data();
  g.sqd = sqd.data();
  std::vector<double> nrm(18, NAN);
  std::vector<float> curv(6, -1.0f);
  dacpo_err err{};
  ASSERT_EQ(dacpo_normals_pca(&dc.c, &g, 4, 1, nrm.data(), curv.data(), &err),
            DACPO_OK);
  expectUnitFinite(nrm, curv);
  for (float c : curv)
    EXPECT_EQ(c, 0.0f);
  // curvature may be skipped
  ASSERT_EQ(dacpo_normals_pca(&dc.c, &g, 0, 1, nrm.data(), nullptr, &err), DACPO_OK);
  EXPECT_NEAR(norm3(&nrm[0]), 1.0, 1e-12);
}

TEST(DacpoNormals, FarFromOriginStaysAccurate)
{
  // A 1 mm grid on a tilted plane, a kilometre from the origin.
  std::vector<double> p;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) {
      double x = 1000.0 + 0.001 * i, y = -2000.0 + 0.001 * j;
      p.insert(p.end(), {x, y, 500.0 + 0.5 * (x - 1000.0) + 0.25 * (y + 2000.0)});
    }
  DoubleCloud dc(p);
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&dc.c, 10, nullptr, 1, nullptr, &g.g, &err), DACPO_OK);
  std::vector<double> nrm(p.size());
  std::vector<float> curv(p.size() / 3);
  ASSERT_EQ(dacpo_normals_pca(&dc.c, &g.g, 10, 1, nrm.data(), curv.data(), &err),
            DACPO_OK);
  const double truth[3] = {-0.5, -0.25, 1.0};
  for (size_t i = 0; i < curv.size(); ++i)
    ASSERT_LT(axisError(&nrm[3 * i], truth), 1e-6) << "point " << i;
}

TEST(DacpoNormals, ThreadsDoNotChangeResults)
{
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> p(3 * 10000);
  for (double& v : p)
    v = u(rng);
  DoubleCloud dc(p);
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&dc.c, 10, nullptr, 2, nullptr, &g.g, &err), DACPO_OK);
  std::vector<double> n1(p.size()), n2(p.size());
  std::vector<float> c1(10000), c2(10000);
  ASSERT_EQ(dacpo_normals_pca(&dc.c, &g.g, 10, 1, n1.data(), c1.data(), &err),
            DACPO_OK);
  ASSERT_EQ(dacpo_normals_pca(&dc.c, &g.g, 10, 2, n2.data(), c2.data(), &err),
            DACPO_OK);
  EXPECT_EQ(n1, n2);
  EXPECT_EQ(c1, c2);
}

TEST(DacpoNormals, RejectsBadArguments)
{
  DoubleCloud dc({0, 0, 0, 1, 0, 0, 0, 1, 0});
  Graph g;
  dacpo_err err{};
  ASSERT_EQ(dacpo_knn_build(&dc.c, 2, nullptr, 1, nullptr, &g.g, &err), DACPO_OK);
  std::vector<double> nrm(9);
  EXPECT_EQ(dacpo_normals_pca(&dc.c, &g.g, 3, 1, nrm.data(), nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_normals_pca(&dc.c, nullptr, 2, 1, nrm.data(), nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_normals_pca(&dc.c, &g.g, 2, 1, nullptr, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  // three points span a plane: the normal is z
  ASSERT_EQ(dacpo_normals_pca(&dc.c, &g.g, 2, 1, nrm.data(), nullptr, &err), DACPO_OK);
  EXPECT_NEAR(std::fabs(nrm[2]), 1.0, 1e-12);
}

namespace {

// Floor z = 0, x in [0, 0.6), y in [0, 0.6) (the first *floor_points points),
// and a wall x = 0.6, z in (0, 0.4], sampled at random at about 2 cm spacing.
std::vector<double>
floorAndWall(size_t* floor_points)
{
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> p;
  for (int i = 0; i < 900; ++i)
    p.insert(p.end(), {0.6 * u(rng), 0.6 * u(rng), 0.0});
  *floor_points = p.size() / 3;
  for (int i = 0; i < 600; ++i)
    p.insert(p.end(), {0.6, 0.6 * u(rng), 0.001 + 0.399 * u(rng)});
  return p;
}

} // namespace

namespace {

// Mean |sin| of the axes of points [begin, end) (those passing keep) against
// the unit normal want.
template <typename Keep>
double
meanAxisError(const std::vector<double>& axes,
              size_t begin,
              size_t end,
              const double want[3],
              Keep keep)
{
  double sum = 0.0;
  size_t m = 0;
  for (size_t i = begin; i < end; ++i)
    if (keep(i)) {
      sum += axisError(&axes[3 * i], want);
      ++m;
    }
  return m ? sum / static_cast<double>(m) : -1.0;
}

// Mean |sin| against +z of the axes of floorAndWall's floor points within
// 5 cm of the wall.
double
nearWallError(const std::vector<double>& p,
              size_t floor_points,
              const std::vector<double>& axes)
{
  const double up[3] = {0.0, 0.0, 1.0};
  auto near_wall = [&](size_t i) { return p[3 * i] >= 0.6 - 0.05; };
  return meanAxisError(axes, 0, floor_points, up, near_wall);
}

// floorAndWall's open floor: away from the wall and the edges.
bool
openFloor(const std::vector<double>& p, size_t i)
{
  return p[3 * i] > 0.1 && p[3 * i] < 0.3 && p[3 * i + 1] > 0.1 && p[3 * i + 1] < 0.5;
}

struct TwoNormals {
  std::vector<double> plain, adaptive;
};

// Plain PCA over 16 neighbours and the adaptive choice among 12 / 16 / 24.
TwoNormals
plainAndAdaptive(DoubleCloud& dc, size_t graph_k)
{
  Graph g;
  dacpo_err err{};
  TwoNormals t;
  t.plain.resize(dc.xyz.size());
  t.adaptive.resize(dc.xyz.size());
  EXPECT_EQ(dacpo_knn_build(&dc.c, graph_k, nullptr, 1, nullptr, &g.g, &err), DACPO_OK);
  EXPECT_EQ(dacpo_normals_pca(&dc.c, &g.g, 16, 1, t.plain.data(), nullptr, &err),
            DACPO_OK);
  EXPECT_EQ(dacpo_normals_pca_scaled(&dc.c, &g.g, 16, 1, 2, t.adaptive.data(), nullptr, &err),
            DACPO_OK)
      << err.msg;
  return t;
}

} // namespace

TEST(DacpoNormals, AdaptiveScaleWidth)
{
  EXPECT_EQ(dacpo_normals_width(16, 0), 16u);
  EXPECT_EQ(dacpo_normals_width(16, 1), 24u);
  EXPECT_EQ(dacpo_normals_width(3, 1), 5u);
}

// A sparse corner: the floor points next to a wall see the wall among their
// 16 nearest; the flatter 12 tilt less (measured: mean |sin| within 2.5
// spacings of the wall 0.344 plain, 0.303 adaptive). The open floor stays exact.
TEST(DacpoNormals, AdaptiveScaleKeepsAxesOffTheOtherFaceOfACorner)
{
  size_t floor_points = 0;
  const std::vector<double> p = floorAndWall(&floor_points);
  DoubleCloud dc(p);
  const TwoNormals t = plainAndAdaptive(dc, 24);
  const double up[3] = {0.0, 0.0, 1.0};
  const double plain = nearWallError(p, floor_points, t.plain);
  const double adaptive = nearWallError(p, floor_points, t.adaptive);
  std::printf("corner: mean |sin| plain %.4f adaptive %.4f\n", plain, adaptive);
  EXPECT_LT(adaptive, 0.92 * plain);
  for (size_t i = 0; i < floor_points; ++i)
    if (openFloor(p, i))
      ASSERT_LT(axisError(&t.adaptive[3 * i], up), 1e-9) << i;
}

// Noise along the normal (sigma = 0.3 spacing): the larger neighbourhood
// averages it, so the adaptive axes are better than 16 alone (measured: mean
// |sin| 0.098 plain, 0.073 adaptive).
TEST(DacpoNormals, AdaptiveScaleAveragesNoiseOnAPlane)
{
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.006);
  std::vector<double> p;
  for (int i = 0; i < 2500; ++i)
    p.insert(p.end(), {u(rng), u(rng), noise(rng)});
  DoubleCloud dc(p);
  const TwoNormals t = plainAndAdaptive(dc, 24);
  const double up[3] = {0.0, 0.0, 1.0};
  auto inner = [&](size_t i) {
    return p[3 * i] > 0.1 && p[3 * i] < 0.9 && p[3 * i + 1] > 0.1 && p[3 * i + 1] < 0.9;
  };
  const double plain = meanAxisError(t.plain, 0, p.size() / 3, up, inner);
  const double adaptive = meanAxisError(t.adaptive, 0, p.size() / 3, up, inner);
  std::printf("noisy plane: mean |sin| plain %.4f adaptive %.4f\n", plain, adaptive);
  EXPECT_LT(adaptive, 0.95 * plain);
}

// A single depth frame's slanted wall (slope 1/2, 1 cm grid): depth quantised
// into terraces. 12 neighbours on one terrace are flat with the wrong axis;
// the strip guard (l1 / l2 >= 0.3) keeps them out where a terrace is about one
// point wide (step 6 mm: mean |sin| 0.078 plain, 0.058 adaptive, the 24
// averaging the steps), but not where it is 2.4 points wide (step 12 mm: 0.106
// -> 0.154, 12 neighbours of one terrace pass as a patch). That is the cost the
// depth frames pay (their worst seed, README). A guard of 0.4 passes both here
// but took the 15 frames from 2.03 to 2.27 % and the 18 rooms from 5.20 to 5.29
// % (seeds 1-5, median), so the bound below records today's behaviour.
static double
terraceErrors(double step, double* plain, double* adaptive)
{
  std::vector<double> p;
  for (int ix = 0; ix < 60; ++ix)
    for (int iy = 0; iy < 60; ++iy) {
      const double x = 0.01 * ix, y = 0.01 * iy;
      p.insert(p.end(), {x, y, step * std::round(0.5 * x / step)});
    }
  DoubleCloud dc(p);
  const TwoNormals t = plainAndAdaptive(dc, 24);
  double wall[3] = {-0.5, 0.0, 1.0};
  const double l = norm3(wall);
  for (double& w : wall)
    w /= l;
  auto inner = [&](size_t i) {
    return p[3 * i] > 0.05 && p[3 * i] < 0.55 && p[3 * i + 1] > 0.05 &&
           p[3 * i + 1] < 0.55;
  };
  *plain = meanAxisError(t.plain, 0, p.size() / 3, wall, inner);
  *adaptive = meanAxisError(t.adaptive, 0, p.size() / 3, wall, inner);
  std::printf("terraces %.3f: mean |sin| plain %.4f adaptive %.4f\n", step, *plain,
              *adaptive);
  return *adaptive / *plain;
}

TEST(DacpoNormals, AdaptiveScaleOnDepthTerraces)
{
  double plain, adaptive;
  EXPECT_LT(terraceErrors(0.006, &plain, &adaptive), 0.85);
  const double wide = terraceErrors(0.012, &plain, &adaptive);
  EXPECT_GT(wide, 1.2); // the known cost: 12 neighbours of one terrace
  EXPECT_LT(wide, 1.6);
}

// A graph narrower than 3/2 x normal_k clamps the larger scale: still unit
// axes, and on an exact plane still exact.
TEST(DacpoNormals, AdaptiveScaleWithANarrowGraph)
{
  std::vector<double> p;
  for (int ix = 0; ix < 20; ++ix)
    for (int iy = 0; iy < 20; ++iy)
      p.insert(p.end(), {0.01 * ix, 0.01 * iy + 0.003 * ix, 0.0});
  DoubleCloud dc(p);
  const TwoNormals t = plainAndAdaptive(dc, 16);
  const double up[3] = {0.0, 0.0, 1.0};
  for (size_t i = 0; i < p.size() / 3; ++i) {
    ASSERT_NEAR(norm3(&t.adaptive[3 * i]), 1.0, 1e-12);
    ASSERT_LT(axisError(&t.adaptive[3 * i], up), 1e-9);
  }
}

namespace {

// A 1 m x 1 m plane z = 0 seen as `copies` offset copies (views fused with a
// registration error): each copy its own random sample of `per_copy` points,
// lifted by a height uniform in [-lift, lift] and tilted by up to 0.3 degrees,
// so the union is a layer about as thick as its spacing.
std::vector<double>
planeCopies(int copies, int per_copy, double lift, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> p;
  for (int c = 0; c < copies; ++c) {
    const double h = lift * (2.0 * u(rng) - 1.0);
    const double tx = 0.005 * (2.0 * u(rng) - 1.0), ty = 0.005 * (2.0 * u(rng) - 1.0);
    for (int i = 0; i < per_copy; ++i) {
      const double x = u(rng), y = u(rng);
      p.insert(p.end(), {x, y, h + tx * (x - 0.5) + ty * (y - 0.5)});
    }
  }
  return p;
}

struct CopyScaled {
  std::vector<double> before, after;
  size_t changed = 0;
};

// Adaptive PCA axes (normal_k 16), then dacpo_normals_copy_scale on them.
CopyScaled
copyScaled(DoubleCloud& dc, unsigned threads)
{
  Graph g;
  dacpo_err err{};
  CopyScaled r;
  EXPECT_EQ(dacpo_knn_build(&dc.c, 24, nullptr, 1, nullptr, &g.g, &err), DACPO_OK);
  EXPECT_EQ(
      dacpo_normals_pca_scaled(&dc.c, &g.g, 16, 1, 1, dc.nrm.data(), nullptr, &err),
      DACPO_OK);
  r.before = dc.nrm;
  std::vector<float> curv(dc.c.n, -1.0f);
  EXPECT_EQ(dacpo_normals_copy_scale(
                &dc.c, 16, threads, dc.nrm.data(), curv.data(), &r.changed, &err),
            DACPO_OK)
      << err.msg;
  r.after = dc.nrm;
  for (size_t i = 0; i < dc.c.n; ++i)
    if (curv[i] != -1.0f) // only the replaced axes get a new variation
      EXPECT_TRUE(curv[i] >= 0.0f && curv[i] <= 1.0f / 3.0f + 1e-6f) << i;
  return r;
}

// The axes of planeCopies() over the inner 80 % of the plane, before and
// after dacpo_normals_copy_scale: mean |sin| to the plane's axis and the share
// over 30 degrees off it (printed with `what`).
struct PlaneAxes {
  double mean_before = 0.0, mean_after = 0.0, off_before = 0.0, off_after = 0.0;
};

PlaneAxes
planeAxes(const char* what, const std::vector<double>& p, const CopyScaled& r)
{
  const double up[3] = {0.0, 0.0, 1.0};
  auto inner = [&](size_t i) {
    return p[3 * i] > 0.1 && p[3 * i] < 0.9 && p[3 * i + 1] > 0.1 && p[3 * i + 1] < 0.9;
  };
  const size_t n = p.size() / 3;
  PlaneAxes a;
  a.mean_before = meanAxisError(r.before, 0, n, up, inner);
  a.mean_after = meanAxisError(r.after, 0, n, up, inner);
  size_t m = 0;
  for (size_t i = 0; i < n; ++i)
    if (inner(i)) {
      ++m;
      a.off_before += axisError(&r.before[3 * i], up) > 0.5; // 30 degrees
      a.off_after += axisError(&r.after[3 * i], up) > 0.5;
    }
  a.off_before *= 100.0 / (double)m;
  a.off_after *= 100.0 / (double)m;
  std::printf("%s: mean |sin| %.4f -> %.4f, over 30 deg %.2f %% -> %.2f %% (%zu axes "
              "replaced)\n",
              what,
              a.mean_before,
              a.mean_after,
              a.off_before,
              a.off_after,
              r.changed);
  return a;
}

} // namespace

// Six copies of a plane lifted by up to 1 cm at a spacing of about 1 cm: the
// 16 nearest make a layer about as thick as it is wide and PCA's axis is
// noise there; where it turns at twice the neighbours, a larger scale that
// holds gives the plane's axis. Measured (seed 3): axes over 30 degrees off
// 5.33 % -> 0.10 %, mean |sin| 0.200 -> 0.156 (axes within 20 degrees of
// twice their neighbours stay).
TEST(DacpoNormals, CopyScaleSteadiesTheAxesOfOffsetCopies)
{
  std::vector<double> p = planeCopies(6, 1500, 0.01, 3);
  DoubleCloud dc(p);
  const CopyScaled r = copyScaled(dc, 2);
  const PlaneAxes a = planeAxes("plane copies", p, r);
  const size_t n = p.size() / 3;
  EXPECT_GT(r.changed, n / 10);
  EXPECT_LT(a.mean_after, 0.85 * a.mean_before);
  EXPECT_LT(a.off_after, a.off_before / 10);
  for (size_t i = 0; i < n; ++i)
    ASSERT_NEAR(norm3(&r.after[3 * i]), 1.0, 1e-12) << i;
}

// Sixteen copies lifted by up to 5 cm at about the same spacing make a layer
// 10 cm thick: PCA's axis still turns between 64 and 128 neighbours and
// holds only from 128-256 (20 mm registration errors in real fused scans do
// this), so the scales go on doubling up to 32 x normal_k. Measured (seed 5):
// over 30 degrees 44.64 % -> 13.57 %, mean |sin| 0.486 -> 0.278; scales up to
// 4 x normal_k only (checked against 8 x) give 28.61 % and 0.386.
TEST(DacpoNormals, CopyScaleReachesWiderCopies)
{
  std::vector<double> p = planeCopies(16, 600, 0.05, 5);
  DoubleCloud dc(p);
  const CopyScaled r = copyScaled(dc, 2);
  const PlaneAxes a = planeAxes("wider copies", p, r);
  EXPECT_GT(r.changed, p.size() / 3 / 4);
  EXPECT_LT(2.5 * a.off_after, a.off_before);
  EXPECT_LT(a.mean_after, 0.65 * a.mean_before);
}

// Where the axis is steady already (the open floor, exact) it stays. Next to
// a sparse corner the larger neighbourhoods turn towards the wall together
// and pass the test: 20 floor points within 5 cm of the wall take a more
// tilted axis (mean |sin| 0.303 -> 0.367). That is the rule's known cost, and
// why it runs only where the floor shows copies; the bounds record it.
TEST(DacpoNormals, CopyScaleKeepsSteadyAxesAndTiltsASparseCorner)
{
  size_t floor_points = 0;
  const std::vector<double> p = floorAndWall(&floor_points);
  DoubleCloud dc(p);
  const CopyScaled r = copyScaled(dc, 1);
  const double before = nearWallError(p, floor_points, r.before);
  const double after = nearWallError(p, floor_points, r.after);
  std::printf("corner: mean |sin| %.4f -> %.4f (%zu axes replaced)\n",
              before,
              after,
              r.changed);
  EXPECT_LT(r.changed, p.size() / 3 / 20);
  EXPECT_LT(after, before + 0.1);
  for (size_t i = 0; i < floor_points; ++i)
    if (openFloor(p, i))
      ASSERT_EQ(std::memcmp(&r.after[3 * i], &r.before[3 * i], 3 * sizeof(double)), 0)
          << i;
}

TEST(DacpoNormals, CopyScaleDoesNotDependOnTheThreads)
{
  const std::vector<double> p = planeCopies(4, 1000, 0.01, 8);
  DoubleCloud one(p), two(p);
  const CopyScaled a = copyScaled(one, 1), b = copyScaled(two, 2);
  EXPECT_EQ(a.changed, b.changed);
  EXPECT_EQ(
      std::memcmp(a.after.data(), b.after.data(), a.after.size() * sizeof(double)), 0);
}

// Too few points for 8 x normal_k neighbours: nothing changes.
TEST(DacpoNormals, CopyScaleOnATinyCloudIsANoOp)
{
  const std::vector<double> p = planeCopies(2, 60, 0.01, 1);
  DoubleCloud dc(p);
  const CopyScaled r = copyScaled(dc, 1);
  EXPECT_EQ(r.changed, 0u);
  EXPECT_EQ(r.after, r.before);
}
