// SPDX-License-Identifier: BSD-3-Clause
// Triangle rasterizer with z-buffer (support of stage 4b): coverage against
// analytic areas, crack-free meshes, interpolated depth, nearest-wins.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

extern "C" {
#include "dacpo_raster.h"
}

namespace {

struct Raster {
  dacpo_raster r{};
  Raster(size_t w, size_t h)
  {
    dacpo_err err{};
    EXPECT_EQ(dacpo_raster_init(&r, w, h, &err), DACPO_OK) << err.msg;
  }
  ~Raster() { dacpo_raster_free(&r); }
  size_t
  filled() const
  {
    size_t n = 0;
    for (size_t i = 0; i < r.width * r.height; ++i)
      n += r.owner[i] >= 0 ? 1 : 0;
    return n;
  }
};

double
tri_area(const double* a, const double* b, const double* c)
{
  return 0.5 * std::fabs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
}

double
tri_perimeter(const double* a, const double* b, const double* c)
{
  auto d = [](const double* p, const double* q) {
    return std::hypot(p[0] - q[0], p[1] - q[1]);
  };
  return d(a, b) + d(b, c) + d(c, a);
}

// Is (x, y) strictly inside triangle abc (either winding)?
bool
strictly_inside(const double* a, const double* b, const double* c, double x, double y)
{
  auto e = [](const double* p, const double* q, double px, double py) {
    return (q[0] - p[0]) * (py - p[1]) - (q[1] - p[1]) * (px - p[0]);
  };
  // distances to the edge lines, with a margin for the 1/256-pixel snapping
  auto len = [](const double* p, const double* q) {
    return std::hypot(q[0] - p[0], q[1] - p[1]);
  };
  double e0 = e(a, b, x, y) / len(a, b), e1 = e(b, c, x, y) / len(b, c),
         e2 = e(c, a, x, y) / len(c, a);
  const double m = 0.01;
  return (e0 > m && e1 > m && e2 > m) || (e0 < -m && e1 < -m && e2 < -m);
}

} // namespace

TEST(DacpoRaster, InitRejectsBadSizes)
{
  dacpo_raster r;
  dacpo_err err{};
  EXPECT_EQ(dacpo_raster_init(&r, 0, 10, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_raster_init(&r, 10, DACPO_RASTER_MAX_SIZE + 1, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  dacpo_raster_free(&r); // zeroed on failure: safe
  dacpo_raster_free(nullptr);
}

TEST(DacpoRaster, CoverageMatchesAnalyticArea)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-20.0, 220.0); // partly outside too
  Raster R(200, 200);
  int tested = 0;
  for (int it = 0; it < 200; ++it) {
    double a[3] = {U(rng), U(rng), 1.0}, b[3] = {U(rng), U(rng), 1.0},
           c[3] = {U(rng), U(rng), 1.0};
    bool inside = true;
    for (const double* p : {a, b, c})
      inside = inside && p[0] >= 0 && p[0] <= 200 && p[1] >= 0 && p[1] <= 200;
    dacpo_raster_clear(&R.r);
    size_t n = dacpo_raster_triangle(&R.r, a, b, c, 3);
    EXPECT_EQ(n, R.filled());
    // every pixel centre strictly inside is covered, none strictly outside is
    for (size_t y = 0; y < 200; ++y)
      for (size_t x = 0; x < 200; ++x) {
        double px = x + 0.5, py = y + 0.5;
        int32_t o = R.r.owner[y * 200 + x];
        if (strictly_inside(a, b, c, px, py))
          ASSERT_EQ(o, 3) << "it " << it << " pixel " << x << "," << y;
        else if (o >= 0) {
          // covered but not strictly inside: must be on the boundary within snapping
          double aa[3] = {a[0], a[1]}, bb[3] = {b[0], b[1]}, cc[3] = {c[0], c[1]};
          double total = tri_area(aa, bb, cc);
          double p[2] = {px, py};
          double s = tri_area(p, bb, cc) + tri_area(aa, p, cc) + tri_area(aa, bb, p);
          ASSERT_LT(s - total, 0.01 * tri_perimeter(aa, bb, cc) + 1e-6);
        }
      }
    if (inside) {
      ++tested;
      double area = tri_area(a, b, c), per = tri_perimeter(a, b, c);
      EXPECT_NEAR((double)n, area, 0.5 * per + 1.0) << "triangle " << it;
    }
  }
  EXPECT_GT(tested, 2);

  // a big axis-aligned right triangle: exact count is known
  // (0,0)-(100,0)-(0,100): centres (x+.5, y+.5) with x + y + 1 < 100 strictly, plus
  // the hypotenuse centres x + y + 1 == 100 owned or not by the tie rule.
  dacpo_raster_clear(&R.r);
  double p0[3] = {0, 0, 0}, p1[3] = {100, 0, 0}, p2[3] = {0, 100, 0};
  size_t n = dacpo_raster_triangle(&R.r, p0, p1, p2, 0);
  size_t strict = 0, on = 0;
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 100; ++x) {
      if (x + y + 1 < 100)
        ++strict;
      else if (x + y + 1 == 100)
        ++on;
    }
  EXPECT_TRUE(n == strict || n == strict + on)
      << n << " vs " << strict << " (+" << on << ")";
}

TEST(DacpoRaster, SharedEdgesNeitherCrackNorOverlap)
{
  // A perturbed grid mesh over [10.25, 190.75]^2, drawn at one depth: every pixel
  // centre inside the outer square is covered exactly once.
  const int n = 17;
  const double lo = 10.25, hi = 190.75;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> J(
      -0.2, 0.2); // small enough to keep every cell convex
  std::vector<double> v;
  double h = (hi - lo) / n;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      double x = lo + i * h, y = lo + j * h;
      if (i > 0 && i < n && j > 0 && j < n) {
        x += J(rng) * h;
        y += J(rng) * h;
      }
      v.insert(v.end(), {x, y, 2.0});
    }
  Raster R(200, 200);
  size_t total = 0;
  int32_t id = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      int q00 = j * (n + 1) + i, q10 = q00 + 1, q01 = q00 + n + 1, q11 = q01 + 1;
      // alternate diagonals and windings
      if ((i + j) % 2) {
        total +=
            dacpo_raster_triangle(&R.r, &v[3 * q00], &v[3 * q10], &v[3 * q11], id++);
        total +=
            dacpo_raster_triangle(&R.r, &v[3 * q00], &v[3 * q01], &v[3 * q11], id++);
      }
      else {
        total +=
            dacpo_raster_triangle(&R.r, &v[3 * q00], &v[3 * q10], &v[3 * q01], id++);
        total +=
            dacpo_raster_triangle(&R.r, &v[3 * q11], &v[3 * q01], &v[3 * q10], id++);
      }
    }
  // centres x + 0.5 in [10.25, 190.75): x = 10 .. 190 -> 181 per axis
  size_t expected = 181 * 181;
  EXPECT_EQ(total, expected);
  EXPECT_EQ(R.filled(), expected);
}

TEST(DacpoRaster, TieRuleOnEdgesThroughPixelCentres)
{
  // Unperturbed grid with every vertex on a pixel centre: many centres lie
  // exactly on shared edges and diagonals; each must be covered exactly once.
  const int n = 17;
  std::vector<double> v;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      v.insert(v.end(), {10.5 + 10.0 * i, 10.5 + 10.0 * j, 0.0});
  Raster R(200, 200);
  size_t total = 0;
  int32_t id = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      int q00 = j * (n + 1) + i, q10 = q00 + 1, q01 = q00 + n + 1, q11 = q01 + 1;
      if ((i + j) % 2) {
        total +=
            dacpo_raster_triangle(&R.r, &v[3 * q00], &v[3 * q10], &v[3 * q11], id++);
        total +=
            dacpo_raster_triangle(&R.r, &v[3 * q11], &v[3 * q01], &v[3 * q00], id++);
      }
      else {
        total +=
            dacpo_raster_triangle(&R.r, &v[3 * q00], &v[3 * q10], &v[3 * q01], id++);
        total +=
            dacpo_raster_triangle(&R.r, &v[3 * q11], &v[3 * q01], &v[3 * q10], id++);
      }
    }
  EXPECT_EQ(total, R.filled()); // no centre counted twice
  // the tie rule makes the square half-open, [10.5, 180.5)^2: two of its sides
  // are kept, two are left to a neighbour -> centres 10.5 .. 179.5, 170 x 170
  EXPECT_EQ(R.filled(), 170u * 170u);
  for (size_t y = 10; y < 180; ++y)
    for (size_t x = 10; x < 180; ++x)
      ASSERT_GE(R.r.owner[y * 200 + x], 0) << x << "," << y;
}

TEST(DacpoRaster, DepthIsInterpolatedLinearly)
{
  // plane z = 0.3 x - 0.2 y + 5
  auto z = [](double x, double y) { return 0.3 * x - 0.2 * y + 5.0; };
  double a[3] = {12.3, 7.9, 0}, b[3] = {140.6, 30.2, 0}, c[3] = {55.5, 120.25, 0};
  for (double* p : {a, b, c})
    p[2] = z(p[0], p[1]);
  Raster R(160, 160);
  size_t n = dacpo_raster_triangle(&R.r, a, b, c, 1);
  ASSERT_GT(n, 1000u);
  double worst = 0;
  for (size_t y = 0; y < 160; ++y)
    for (size_t x = 0; x < 160; ++x)
      if (R.r.owner[y * 160 + x] == 1)
        worst =
            std::fmax(worst, std::fabs(R.r.depth[y * 160 + x] - z(x + 0.5, y + 0.5)));
      else
        EXPECT_TRUE(std::isinf(R.r.depth[y * 160 + x]));
  // snapping moves vertices by <= 1/512 px; the gradient is < 0.4 per px
  EXPECT_LT(worst, 2e-3);
}

TEST(DacpoRaster, NearerTriangleWinsInEitherOrder)
{
  double a0[3] = {5, 5, 3.0}, a1[3] = {90, 10, 3.0}, a2[3] = {20, 95, 3.0};
  double b0[3] = {30, 0, 1.0}, b1[3] = {99, 60, 1.0}, b2[3] = {10, 70, 1.0};
  for (int order = 0; order < 2; ++order) {
    Raster R(100, 100);
    if (order == 0) {
      dacpo_raster_triangle(&R.r, a0, a1, a2, 0);
      dacpo_raster_triangle(&R.r, b0, b1, b2, 1);
    }
    else {
      dacpo_raster_triangle(&R.r, b0, b1, b2, 1);
      dacpo_raster_triangle(&R.r, a0, a1, a2, 0);
    }
    size_t both = 0;
    for (size_t y = 0; y < 100; ++y)
      for (size_t x = 0; x < 100; ++x) {
        bool ina = strictly_inside(a0, a1, a2, x + 0.5, y + 0.5);
        bool inb = strictly_inside(b0, b1, b2, x + 0.5, y + 0.5);
        int32_t o = R.r.owner[y * 100 + x];
        if (inb) {
          EXPECT_EQ(o, 1);
        }
        else if (ina) {
          EXPECT_EQ(o, 0);
        }
        both += (ina && inb) ? 1 : 0;
      }
    EXPECT_GT(both, 500u);
  }

  // two interpenetrating triangles: the owner flips where their depths cross
  double c0[3] = {0, 0, 0}, c1[3] = {100, 0, 10}, c2[3] = {0, 100, 0}; // z = x / 10
  double d0[3] = {0, 0, 5}, d1[3] = {100, 0, 5}, d2[3] = {0, 100, 5};  // z = 5
  Raster R(100, 100);
  dacpo_raster_triangle(&R.r, c0, c1, c2, 7);
  dacpo_raster_triangle(&R.r, d0, d1, d2, 8);
  for (size_t y = 0; y < 100; y += 3)
    for (size_t x = 0; x + y + 2 < 100; x += 3) {
      double zc = (x + 0.5) / 10.0;
      if (std::fabs(zc - 5.0) < 0.05)
        continue;
      EXPECT_EQ(R.r.owner[y * 100 + x], zc < 5.0 ? 7 : 8) << x << "," << y;
    }
}

TEST(DacpoRaster, DegenerateAndNonFiniteTrianglesDrawNothing)
{
  Raster R(50, 50);
  double a[3] = {1, 1, 0}, b[3] = {40, 40, 0}, c[3] = {20, 20, 0}; // collinear
  EXPECT_EQ(dacpo_raster_triangle(&R.r, a, b, c, 0), 0u);
  double d[3] = {NAN, 3, 0};
  EXPECT_EQ(dacpo_raster_triangle(&R.r, a, b, d, 0), 0u);
  double e[3] = {1e30, 3, 0};
  EXPECT_EQ(dacpo_raster_triangle(&R.r, a, b, e, 0), 0u);
  double f[3] = {-100, -100, 0}, g[3] = {-50, -100, 0},
         h[3] = {-100, -50, 0}; // off image
  EXPECT_EQ(dacpo_raster_triangle(&R.r, f, g, h, 0), 0u);
  EXPECT_EQ(R.filled(), 0u);
  EXPECT_EQ(dacpo_raster_triangle(nullptr, a, b, f, 0), 0u);
}

TEST(DacpoRaster, ClippedTriangleAndClear)
{
  Raster R(64, 64);
  // covers the whole image and more
  double a[3] = {-100, -100, 1}, b[3] = {300, -100, 1}, c[3] = {-100, 300, 1};
  EXPECT_EQ(dacpo_raster_triangle(&R.r, a, b, c, 4), 64u * 64u);
  EXPECT_EQ(R.filled(), 64u * 64u);
  dacpo_raster_clear(&R.r);
  EXPECT_EQ(R.filled(), 0u);
  for (size_t i = 0; i < 64 * 64; ++i)
    ASSERT_TRUE(std::isinf(R.r.depth[i]));
  // a small triangle after clearing: only its pixels
  double d[3] = {10, 10, 0}, e[3] = {20, 10, 0}, f[3] = {10, 20, 0};
  size_t n = dacpo_raster_triangle(&R.r, d, e, f, 1);
  EXPECT_EQ(R.filled(), n);
  EXPECT_NEAR((double)n, 50.0, 0.5 * (20 + std::sqrt(200.0)) + 1);
}

// One rasterization serves a view and its opposite: the far image handed over
// by dacpo_raster_take_far equals the near image of the same triangles drawn
// with z negated (random overlapping triangles, exact depth ties included, in
// the same order: ties keep the triangle drawn first in both). Pixels the
// caller added around the drawn rectangle are emptied, and the far image is
// empty again afterwards.
TEST(DacpoRaster, FarImageIsTheOppositeView)
{
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(2.0, 46.0), Z(-3.0, 3.0);
  std::vector<std::array<double, 9>> tris;
  for (int t = 0; t < 60; ++t) {
    std::array<double, 9> v{};
    const double z = t % 7 == 0 ? 1.0 : Z(rng); // every 7th: one depth, ties
    for (int k = 0; k < 3; ++k) {
      v[3 * k] = U(rng);
      v[3 * k + 1] = U(rng);
      v[3 * k + 2] = t % 7 == 0 ? z : Z(rng);
    }
    tris.push_back(v);
  }
  Raster both(48, 48), negated(48, 48);
  dacpo_err err{};
  ASSERT_EQ(dacpo_raster_keep_far(&both.r, &err), DACPO_OK) << err.msg;
  for (size_t t = 0; t < tris.size(); ++t) {
    const double* v = tris[t].data();
    dacpo_raster_triangle(&both.r, v, v + 3, v + 6, (int32_t)t);
    double m[9];
    for (int i = 0; i < 9; ++i)
      m[i] = i % 3 == 2 ? -v[i] : v[i];
    dacpo_raster_triangle(&negated.r, m, m + 3, m + 6, (int32_t)t);
  }
  const size_t x0 = both.r.x0, y0 = both.r.y0, x1 = both.r.x1, y1 = both.r.y1;
  ASSERT_LE(x0, x1);
  // the caller's seam closing may write beyond the drawn rectangle
  both.r.x0 = 0, both.r.y0 = 0, both.r.x1 = 47, both.r.y1 = 47;
  both.r.owner[0] = 3, both.r.depth[0] = 0.5f;
  dacpo_raster_take_far(&both.r, x0, y0, x1, y1);
  EXPECT_EQ(both.r.x0, x0);
  EXPECT_EQ(both.r.y1, y1);
  size_t drawn = 0;
  for (size_t p = 0; p < 48 * 48; ++p) {
    EXPECT_EQ(both.r.owner[p], negated.r.owner[p]) << "pixel " << p;
    if (negated.r.owner[p] >= 0) {
      ++drawn;
      EXPECT_EQ(both.r.depth[p], negated.r.depth[p]) << "pixel " << p;
    }
    EXPECT_EQ(both.r.far_owner[p], -1);
  }
  EXPECT_GT(drawn, 500u);
}
