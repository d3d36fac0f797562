// SPDX-License-Identifier: BSD-3-Clause
// The scan-kind test of stage 0 (dacpo_view_kind.c) with known answers: one
// generated scene - a floor, two walls and a box - seen by a pinhole depth
// camera (one point per pixel: density falls with distance and incidence) must
// count as a single view, also after light voxel thinning; the same surfaces
// sampled uniformly, or the camera's points thinned to a coarse grid, must not. Then the pipeline: the kind it
// reports, the one it was given, and the parameters it rejects.
#include <dacpo/dacpo.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <set>
#include <random>
#include <string>
#include <vector>

extern "C" {
#include "dacpo_kdtree.h"
#include "dacpo_view_kind.h"
}
#include "scene_fixture.hpp"

namespace {

struct Cloud {
  std::vector<double> xyz, axes;
  void
  add(double x, double y, double z, double nx, double ny, double nz)
  {
    xyz.insert(xyz.end(), {x, y, z});
    axes.insert(axes.end(), {nx, ny, nz});
  }
  size_t
  size() const
  {
    return xyz.size() / 3;
  }
};

// A room corner: floor y = -1, back wall z = 5, left wall x = -2, and a box
// [-0.5, 0.5] x [-1, 0] x [2.5, 3.5]. nearest(): the first surface a ray from
// the origin along d meets (t and its unit axis), false if none.
bool
nearest(const double d[3], double* t_out, double n_out[3], double lift = 0.0)
{
  double best = INFINITY;
  auto plane = [&](int axis, double at, double lo0, double hi0, double lo1, double hi1) {
    if (std::fabs(d[axis]) < 1e-12)
      return;
    const double t = at / d[axis];
    if (!(t > 1e-9) || t >= best)
      return;
    const int a0 = (axis + 1) % 3, a1 = (axis + 2) % 3;
    const double u = t * d[a0], v = t * d[a1];
    if (u < lo0 || u > hi0 || v < lo1 || v > hi1)
      return;
    best = t;
    n_out[0] = n_out[1] = n_out[2] = 0.0;
    n_out[axis] = 1.0;
  };
  plane(1, -1.0, -2.0, 5.0, -2.0, 2.0);     // floor: axes z (a0), x (a1)
  plane(2, 5.0, -2.0, 2.0, -1.0, 1.5);      // back wall: x, y
  plane(0, -2.0, -1.0, 1.5, 0.0, 5.0);      // left wall: y, z
  plane(1, lift, 2.5, 3.5, -0.5, 0.5);                  // box top
  plane(2, 2.5, -0.5, 0.5, -1.0 + lift, lift);          // box front
  plane(0, 0.5, -1.0 + lift, lift, 2.5, 3.5);           // box right side
  if (lift > 0.0)
    plane(1, -1.0 + lift, 2.5, 3.5, -0.5, 0.5);         // its underside
  *t_out = best;
  return std::isfinite(best);
}

// One point per pixel of a 200 x 150 pinhole image looking along +z (the
// camera at the origin); lift: the box floats that high above the floor.
Cloud
depthFrame(double lift = 0.0)
{
  Cloud c;
  const int w = 200, h = 150;
  const double f = 160.0;
  for (int r = 0; r < h; ++r)
    for (int col = 0; col < w; ++col) {
      double d[3] = {(col - 0.5 * w + 0.5) / f, (r - 0.5 * h + 0.5) / f, 1.0};
      const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + 1.0);
      for (double& x : d)
        x /= len;
      double t, n[3];
      if (nearest(d, &t, n, lift))
        c.add(t * d[0], t * d[1], t * d[2], n[0], n[1], n[2]);
    }
  return c;
}

// The frame's surfaces sampled uniformly by area (random, same point count).
Cloud
uniformSurfaces(size_t count, unsigned seed)
{
  struct Rect {
    int axis;
    double at, lo0, hi0, lo1, hi1;
  };
  const Rect rects[] = {{1, -1.0, -2.0, 5.0, -2.0, 2.0},
                        {2, 5.0, -2.0, 2.0, -1.0, 1.5},
                        {0, -2.0, -1.0, 1.5, 0.0, 5.0},
                        {1, 0.0, 2.5, 3.5, -0.5, 0.5},
                        {2, 2.5, -0.5, 0.5, -1.0, 0.0},
                        {0, 0.5, -1.0, 0.0, 2.5, 3.5}};
  double total = 0.0;
  for (const Rect& r : rects)
    total += (r.hi0 - r.lo0) * (r.hi1 - r.lo1);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud c;
  for (const Rect& r : rects) {
    const size_t m = static_cast<size_t>(count * (r.hi0 - r.lo0) * (r.hi1 - r.lo1) / total);
    for (size_t i = 0; i < m; ++i) {
      double p[3], n[3] = {0.0, 0.0, 0.0};
      p[r.axis] = r.at;
      p[(r.axis + 1) % 3] = r.lo0 + u(rng) * (r.hi0 - r.lo0);
      p[(r.axis + 2) % 3] = r.lo1 + u(rng) * (r.hi1 - r.lo1);
      n[r.axis] = 1.0;
      c.add(p[0], p[1], p[2], n[0], n[1], n[2]);
    }
  }
  return c;
}

// Squared distances of the k nearest of every point (self excluded).
std::vector<float>
neighbourDistances(const Cloud& c, size_t k)
{
  dacpo_err err = {DACPO_OK, {0}};
  dacpo_kdtree* tree = nullptr;
  EXPECT_EQ(dacpo_kdtree_build(c.xyz.data(), c.size(), &tree, &err), DACPO_OK);
  std::vector<float> sqd(c.size() * k);
  std::vector<int32_t> idx(k + 1);
  std::vector<double> d(k + 1);
  for (size_t i = 0; i < c.size(); ++i) {
    dacpo_kdtree_knn(tree, &c.xyz[3 * i], k + 1, idx.data(), d.data());
    for (size_t j = 0; j < k; ++j)
      sqd[i * k + j] = static_cast<float>(d[j + 1]);
  }
  dacpo_kdtree_free(tree);
  return sqd;
}

double
fitOf(const Cloud& c, double* slope = nullptr)
{
  const size_t k = 10;
  const std::vector<float> sqd = neighbourDistances(c, k);
  dacpo_err err = {DACPO_OK, {0}};
  double fit = -2.0;
  EXPECT_EQ(dacpo_single_view_sensor(
                c.xyz.data(), c.axes.data(), c.size(), sqd.data(), k, &fit, slope, nullptr, &err),
            DACPO_OK)
      << err.msg;
  return fit;
}

TEST(DacpoViewKind, DepthFrameIsOneView)
{
  const Cloud frame = depthFrame();
  ASSERT_GT(frame.size(), 20000u);
  double slope = 0.0;
  const double fit = fitOf(frame, &slope);
  RecordProperty("fit", std::to_string(fit));
  EXPECT_GE(fit, DACPO_SINGLE_VIEW_FIT + 0.2);
  EXPECT_GT(slope, 0.7); // a sensor's density follows the model: slope 1
  EXPECT_LT(slope, 1.4);
}

TEST(DacpoViewKind, UniformSamplingIsNotOneView)
{
  const Cloud frame = depthFrame();
  const double fit = fitOf(uniformSurfaces(frame.size(), 7));
  EXPECT_LT(fit, DACPO_SINGLE_VIEW_FIT - 0.1);
}

// The frame thinned by a voxel grid (the first point of every cell kept).
Cloud
voxelThinned(const Cloud& frame, double cell)
{
  Cloud thin;
  std::set<std::array<int64_t, 3>> seen;
  for (size_t i = 0; i < frame.size(); ++i) {
    std::array<int64_t, 3> key;
    for (int d = 0; d < 3; ++d)
      key[d] = static_cast<int64_t>(std::floor(frame.xyz[3 * i + d] / cell));
    if (!seen.insert(key).second)
      continue;
    thin.add(frame.xyz[3 * i],
             frame.xyz[3 * i + 1],
             frame.xyz[3 * i + 2],
             frame.axes[3 * i],
             frame.axes[3 * i + 1],
             frame.axes[3 * i + 2]);
  }
  return thin;
}

// Thinned at 3 cm (16K of 22K points) the density still follows the sensor
// (fit 0.83); at 10 cm (2K points left) it no longer does (0.16): the limit
// the documentation names - pass the kind explicitly for such data.
TEST(DacpoViewKind, VoxelThinnedFrame)
{
  const Cloud frame = depthFrame();
  const Cloud light = voxelThinned(frame, 0.03), heavy = voxelThinned(frame, 0.10);
  ASSERT_GT(light.size(), 10000u);
  ASSERT_GT(heavy.size(), 1500u);
  EXPECT_GE(fitOf(light), DACPO_SINGLE_VIEW_FIT + 0.2);
  EXPECT_LT(fitOf(heavy), DACPO_SINGLE_VIEW_FIT - 0.2);
}

// Where the frame was taken from: the camera stands at the origin. Every
// pixel, and a random half of them (a frame thinned at random, as real clouds
// often are), with the exact axes. Measured: 0.21 and 0.42 m off in a scene
// 5 m deep (the side the sensor is on is what the last sign pass needs).
TEST(DacpoViewKind, SensorIsFoundWhereTheFrameWasTaken)
{
  const Cloud frame = depthFrame();
  Cloud half;
  std::mt19937_64 rng(3);
  for (size_t i = 0; i < frame.size(); ++i)
    if (rng() & 1u)
      half.add(frame.xyz[3 * i],
               frame.xyz[3 * i + 1],
               frame.xyz[3 * i + 2],
               frame.axes[3 * i],
               frame.axes[3 * i + 1],
               frame.axes[3 * i + 2]);
  for (const Cloud* c : std::vector<const Cloud*>{&frame, &half}) {
    const size_t k = 10;
    const std::vector<float> sqd = neighbourDistances(*c, k);
    dacpo_err err = {DACPO_OK, {0}};
    double fit = 0.0, sensor[3] = {9.0, 9.0, 9.0};
    ASSERT_EQ(dacpo_single_view_sensor(
                  c->xyz.data(), c->axes.data(), c->size(), sqd.data(), k, &fit, nullptr,
                  sensor, &err),
              DACPO_OK)
        << err.msg;
    const double off = std::sqrt(sensor[0] * sensor[0] + sensor[1] * sensor[1] +
                                 sensor[2] * sensor[2]);
    printf("%zu points: fit %.3f, sensor (%.3f, %.3f, %.3f), %.3f m from the camera\n",
           c->size(), fit, sensor[0], sensor[1], sensor[2], off);
    EXPECT_GE(fit, DACPO_SINGLE_VIEW_FIT);
    EXPECT_LT(off, 0.5) << "a tenth of the scene's depth";
  }
}

// One view faces its sensor: a frame whose box floats 0.4 m above the floor
// (its own component), oriented with disconnected parts left as they come
// (DISCONNECTED_SEPARATE: nothing relates the box to the room). The last
// sign pass turns every point the sensor sees within 60 degrees of its normal
// to face the sensor, so those come out right whatever sign the box got.
TEST(DacpoViewKind, OneViewFacesItsSensor)
{
  const Cloud frame = depthFrame(0.4);
  std::vector<float> xyz(frame.xyz.begin(), frame.xyz.end());
  size_t turned = 0;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(seed);
    std::vector<float> nrm(frame.xyz.size(), 0.0f);
    dacpo_params p;
    dacpo_params_init(&p);
    p.estimate_normals = 1;
    p.seed = seed;
    p.disconnected = DACPO_DISCONNECTED_SEPARATE;
    dacpo_ctx* ctx = nullptr;
    ASSERT_EQ(dacpo_ctx_create(&ctx), DACPO_OK);
    ASSERT_EQ(dacpo_orient(ctx, &p, nullptr, nullptr, xyz.data(), nrm.data(), frame.size()),
              DACPO_OK)
        << dacpo_ctx_last_error(ctx);
    const dacpo_stats st = *dacpo_ctx_stats(ctx);
    dacpo_ctx_free(ctx);
    EXPECT_EQ(st.scan_kind, DACPO_SCAN_SINGLE_VIEW);
    EXPECT_GE(st.num_components, 2u);
    turned += st.sensor_turned;
    size_t square = 0, wrong = 0;
    for (size_t i = 0; i < frame.size(); ++i) {
      const double* q = &frame.xyz[3 * i];
      const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
      const double* a = &frame.axes[3 * i];
      const double cosine = -(a[0] * q[0] + a[1] * q[1] + a[2] * q[2]) / len;
      if (std::fabs(cosine) < 0.6)
        continue;
      ++square;
      const float* o = &nrm[3 * i];
      const double toward = -(o[0] * q[0] + o[1] * q[1] + o[2] * q[2]);
      wrong += toward <= 0.0;
    }
    printf("seed %llu: %zu of %zu squarely seen points face away, %zu turned\n",
           (unsigned long long)seed,
           wrong,
           square,
           st.sensor_turned);
    EXPECT_GT(square, 10000u);
    EXPECT_EQ(wrong, 0u);
  }
  RecordProperty("sensor_turned", std::to_string(turned));
}

TEST(DacpoViewKind, TooFewPointsAndNullArguments)
{
  dacpo_err err = {DACPO_OK, {0}};
  const double xyz[6] = {0, 0, 0, 1, 0, 0}, axes[6] = {0, 0, 1, 0, 0, 1};
  const float sqd[2] = {1.0f, 1.0f};
  double fit = -2.0;
  EXPECT_EQ(dacpo_single_view_sensor(xyz, axes, 2, sqd, 1, &fit, nullptr, nullptr, &err), DACPO_OK);
  EXPECT_EQ(fit, 0.0);
  EXPECT_EQ(dacpo_single_view_sensor(nullptr, axes, 2, sqd, 1, &fit, nullptr, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_single_view_sensor(xyz, axes, 2, sqd, 1, nullptr, nullptr, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
}

// The pipeline decides the kind once, reports it, and keeps a given one.
dacpo_stats
runOn(const Cloud& c,
      dacpo_scan_kind kind,
      std::vector<float>* normals = nullptr,
      double dipole_c = -1.0,
      double layers = -1.0)
{
  std::vector<float> xyz(c.xyz.begin(), c.xyz.end()), nrm(c.xyz.size());
  dacpo_params p;
  dacpo_params_init(&p);
  p.estimate_normals = 1;
  p.num_threads = 2;
  p.scan_kind = kind;
  p.dipole_c = dipole_c;
  p.dipole_layers = layers;
  dacpo_ctx* ctx = nullptr;
  EXPECT_EQ(dacpo_ctx_create(&ctx), DACPO_OK);
  EXPECT_EQ(dacpo_orient(ctx, &p, nullptr, nullptr, xyz.data(), nrm.data(), c.size()),
            DACPO_OK)
      << dacpo_ctx_last_error(ctx);
  const dacpo_stats s = *dacpo_ctx_stats(ctx);
  dacpo_ctx_free(ctx);
  if (normals)
    *normals = nrm;
  return s;
}

TEST(DacpoViewKind, PipelineReportsTheKind)
{
  const Cloud frame = depthFrame();
  const dacpo_stats single = runOn(frame, DACPO_SCAN_AUTO);
  EXPECT_EQ(single.scan_kind, DACPO_SCAN_SINGLE_VIEW);
  EXPECT_GE(single.single_view_fit, DACPO_SINGLE_VIEW_FIT);

  GeneratedScene room(DACPO_SCENE_ROOM, 20000, 5);
  ASSERT_TRUE(room.ok);
  Cloud rc;
  for (size_t i = 0; i < room.s.n; ++i)
    rc.add(room.s.xyz[3 * i], room.s.xyz[3 * i + 1], room.s.xyz[3 * i + 2], 0, 0, 1);
  const dacpo_stats multi = runOn(rc, DACPO_SCAN_AUTO);
  EXPECT_EQ(multi.scan_kind, DACPO_SCAN_MULTI_VIEW);
  EXPECT_LT(multi.single_view_fit, DACPO_SINGLE_VIEW_FIT);

  const dacpo_stats given = runOn(frame, DACPO_SCAN_MULTI_VIEW);
  EXPECT_EQ(given.scan_kind, DACPO_SCAN_MULTI_VIEW);
  EXPECT_EQ(given.single_view_fit, 0.0);
}

// Two parallel 1 m sheets 2 spacings apart, sampled on a jittered grid: the
// k-th neighbour reaches farther at the rims, which correlates with a
// candidate sensor above their middle (fit 0.54-0.56 on seeds 1-2 without the
// slope guard), but the density hardly follows the model (slope near 0): not
// one view, so their faces keep the two-sheet rule.
TEST(DacpoViewKind, EvenlySampledSheetsAreNotOneView)
{
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    dacpo_scene sc{};
    char msg[256];
    ASSERT_EQ(
        dacpo_scene_parallel_sheets(1.0, 0.02, 0.04, 0.0, seed, &sc, msg, sizeof(msg)),
        0)
        << msg;
    Cloud c;
    for (size_t i = 0; i < sc.n; ++i)
      c.add(sc.xyz[3 * i], sc.xyz[3 * i + 1], sc.xyz[3 * i + 2], 0, 0, 1);
    dacpo_scene_free(&sc);
    const dacpo_stats s = runOn(c, DACPO_SCAN_AUTO);
    EXPECT_EQ(s.scan_kind, DACPO_SCAN_MULTI_VIEW) << "seed " << seed;
    EXPECT_LT(s.single_view_fit, DACPO_SINGLE_VIEW_FIT) << "seed " << seed;
  }
}

// What the kind sets when c, the layer rule and the two-sheet rule are left to
// it (-1): a single view runs with c = 1, layers at 0.5 spacings and no
// two-sheet rule, a scene seen from many places with c = 1.5, layers at 2 and
// the two-sheet rule at 3; given values are kept.
TEST(DacpoViewKind, KindSetsDipoleConstantAndLayers)
{
  const Cloud frame = depthFrame();
  const dacpo_stats single = runOn(frame, DACPO_SCAN_AUTO);
  EXPECT_EQ(single.dipole_c_used, 1.0);
  EXPECT_EQ(single.dipole_layers_used, 0.5);
  EXPECT_EQ(single.dipole_two_sheet_used, 0.0);
  const dacpo_stats multi = runOn(frame, DACPO_SCAN_MULTI_VIEW);
  EXPECT_EQ(multi.dipole_c_used, 1.5);
  EXPECT_EQ(multi.dipole_layers_used, 2.0);
  EXPECT_EQ(multi.dipole_two_sheet_used, 3.0);
  const dacpo_stats given = runOn(frame, DACPO_SCAN_AUTO, nullptr, 2.5, 1.0);
  EXPECT_EQ(given.scan_kind, DACPO_SCAN_SINGLE_VIEW);
  EXPECT_EQ(given.dipole_c_used, 2.5);
  EXPECT_EQ(given.dipole_layers_used, 1.0);
  EXPECT_EQ(given.dipole_two_sheet_used, 0.0);
}

TEST(DacpoViewKind, ParamsRejectUnknownKindAndNonFiniteLayers)
{
  dacpo_params p;
  dacpo_params_init(&p);
  EXPECT_EQ(p.scan_kind, DACPO_SCAN_AUTO);
  EXPECT_LT(p.dipole_layers, 0.0);
  EXPECT_LT(p.dipole_c, 0.0);
  EXPECT_LT(p.dipole_two_sheet, 0.0);
  char msg[256];
  p.scan_kind = static_cast<dacpo_scan_kind>(7);
  EXPECT_EQ(dacpo_params_validate(&p, msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(msg).find("scan_kind"), std::string::npos);
  dacpo_params_init(&p);
  p.dipole_layers = NAN;
  EXPECT_EQ(dacpo_params_validate(&p, msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT);
}

} // namespace
