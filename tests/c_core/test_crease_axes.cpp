// SPDX-License-Identifier: BSD-3-Clause
// Tests for the crease axes of stage 1 (c_core/src/segment/dacpo_crease_axes.c):
// noise averaged out, creases and the faces of thin parts kept. Neighbour
// rows are brute-force k-NN here, so the tests do not depend on dacpo_knn.c.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

extern "C" {
#include "dacpo_crease_axes.h"
}

namespace {

struct Cloud {
  std::vector<double> xyz, nrm;
  std::vector<int32_t> ident, idx;
  std::vector<float> sqd;
  dacpo_cloud c{};
  dacpo_knn_graph g{};

  void
  add(double x, double y, double z, double nx, double ny, double nz)
  {
    xyz.insert(xyz.end(), {x, y, z});
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    nrm.insert(nrm.end(), {nx / len, ny / len, nz / len});
  }

  // Brute-force k nearest neighbours (self excluded), then the views.
  void
  finish(size_t k)
  {
    const size_t n = xyz.size() / 3;
    ident.resize(n);
    idx.assign(n * k, -1);
    sqd.assign(n * k, 0.0f);
    std::vector<std::pair<double, int32_t>> d;
    for (size_t i = 0; i < n; ++i) {
      ident[i] = (int32_t)i;
      d.clear();
      for (size_t j = 0; j < n; ++j) {
        if (j == i)
          continue;
        double s = 0.0;
        for (int a = 0; a < 3; ++a)
          s += (xyz[3 * i + a] - xyz[3 * j + a]) * (xyz[3 * i + a] - xyz[3 * j + a]);
        d.push_back({s, (int32_t)j});
      }
      std::partial_sort(d.begin(), d.begin() + (long)k, d.end());
      for (size_t t = 0; t < k; ++t) {
        idx[i * k + t] = d[t].second;
        sqd[i * k + t] = (float)d[t].first;
      }
    }
    c.n = n;
    c.input_count = n;
    c.xyz = xyz.data();
    c.nrm = nrm.data();
    c.rep_input = ident.data();
    c.input_to_point = ident.data();
    g.n = n;
    g.k = k;
    g.idx = idx.data();
    g.sqd = sqd.data();
  }
};

double
angle_deg(const double* a, const double* b)
{
  const double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  return std::acos(std::min(1.0, std::fabs(c))) * 180.0 / M_PI;
}

std::vector<double>
crease_axes(Cloud& cl, size_t k)
{
  std::vector<double> out(cl.nrm.size(), 0.0);
  dacpo_err err{};
  EXPECT_EQ(dacpo_crease_axes(&cl.c, &cl.g, k, 2, out.data(), &err), DACPO_OK) << err.msg;
  return out;
}

} // namespace

TEST(DacpoCreaseAxes, ScatterOnAPlaneIsAveragedOut)
{
  // axes of a plane tilted at random by up to 25 degrees, as PCA over offset
  // copies of a surface gives them
  Cloud cl;
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> tilt(-0.45, 0.45);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 30; ++x)
      cl.add(x, y, 0.0, tilt(gen), tilt(gen), 1.0);
  cl.finish(16);
  const double up[3] = {0.0, 0.0, 1.0};
  const std::vector<double> out = crease_axes(cl, 16);
  double before = 0.0, after = 0.0;
  for (size_t i = 0; i < cl.c.n; ++i) {
    before += angle_deg(&cl.nrm[3 * i], up);
    after += angle_deg(&out[3 * i], up);
  }
  before /= (double)cl.c.n;
  after /= (double)cl.c.n;
  EXPECT_GT(before, 10.0);
  EXPECT_LT(after, before / 3.0) << "mean error " << before << " -> " << after;
}

TEST(DacpoCreaseAxes, ARightAngledCreaseKeepsBothAxes)
{
  // an L: floor z = 0 (axis +z) meeting a wall x = 0 (axis +x); exact axes stay
  // exact: across the crease a neighbour weighs e^-4 and its axis is an
  // eigenvector of the point's tensor anyway
  Cloud cl;
  for (int y = 0; y < 12; ++y) {
    for (int x = 1; x <= 12; ++x)
      cl.add(x, y, 0.0, 0.0, 0.0, 1.0);
    for (int z = 1; z <= 12; ++z)
      cl.add(0.0, y, z, 1.0, 0.0, 0.0);
  }
  cl.finish(16);
  const std::vector<double> out = crease_axes(cl, 16);
  for (size_t i = 0; i < cl.c.n; ++i)
    ASSERT_LT(angle_deg(&out[3 * i], &cl.nrm[3 * i]), 1e-6) << "point " << i;
}

TEST(DacpoCreaseAxes, TheFacesOfAThinBoardKeepTheirSigns)
{
  // a board 0.5 spacings thick: each face's neighbours include the other face,
  // whose axis is opposite; unsigned averaging keeps both, each output has the
  // sign of its input
  Cloud cl;
  for (int y = 0; y < 15; ++y)
    for (int x = 0; x < 15; ++x) {
      cl.add(x, y, 0.0, 0.05, 0.0, -1.0);
      cl.add(x + 0.5, y + 0.5, 0.5, -0.05, 0.0, 1.0);
    }
  cl.finish(12);
  const std::vector<double> out = crease_axes(cl, 12);
  for (size_t i = 0; i < cl.c.n; ++i) {
    const double* a = &cl.nrm[3 * i];
    const double* o = &out[3 * i];
    EXPECT_GT(a[0] * o[0] + a[1] * o[1] + a[2] * o[2], 0.99) << "point " << i;
  }
}

TEST(DacpoCreaseAxes, BadArgumentsAreRejected)
{
  Cloud cl;
  for (int i = 0; i < 5; ++i)
    cl.add(i, 0.0, 0.0, 0.0, 0.0, 1.0);
  cl.finish(3);
  std::vector<double> out(15);
  dacpo_err err{};
  EXPECT_EQ(dacpo_crease_axes(nullptr, &cl.g, 3, 1, out.data(), &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_crease_axes(&cl.c, &cl.g, 4, 1, out.data(), &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_crease_axes(&cl.c, &cl.g, 3, 1, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  // k = 0: each axis is its own average
  ASSERT_EQ(dacpo_crease_axes(&cl.c, &cl.g, 0, 1, out.data(), &err), DACPO_OK);
  for (size_t i = 0; i < out.size(); ++i)
    EXPECT_DOUBLE_EQ(out[i], cl.nrm[i]);
}
