// SPDX-License-Identifier: BSD-3-Clause
// Stage 0's layered test (dacpo_layered.c): a room fused from views with a
// registration error shows its floor as offset copies, which the thin-part side
// cue would read as the two faces of a solid; the test finds the copies and the
// pipeline leaves the cue out.
//
// Measured on generated rooms (100K points, sigma 2 mm, scene seeds 1-3, the
// ground truth as axes) with -fused 3,0.008,0.2 (dacpo_make_scene): see the
// test's output; two sheets alone 0 (nothing lies beside them).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

extern "C" {
#include "dacpo/dacpo.h"
#include "dacpo_kdtree.h"
#include "dacpo_layered.h"
#include "dacpo_scene.h"
#include "dacpo_sheets_cross.h"
}

#include "scene_fixture.hpp"

namespace {

// A room of `points` points (sigma 2 mm), fused from `views` views 8 mm and
// 0.2 degrees apart (0: not fused).
dacpo_scene_params
roomParams(size_t points, unsigned views, uint64_t seed)
{
  dacpo_scene_params sp = GeneratedScene::params(DACPO_SCENE_ROOM, points, seed);
  sp.noise_sigma = 0.002;
  sp.fused_views = views;
  sp.fused_shift = 0.008;
  sp.fused_angle = 0.2;
  return sp;
}

// The share for n points with their ground-truth normals as axes and the
// squared distances to their 8 nearest neighbours (self excluded).
double
shareOf(const float* xyzf,
        const float* nrmf,
        size_t n,
        double* copies_out = nullptr,
        double* doubled_out = nullptr)
{
  const size_t k = 24;
  std::vector<double> xyz(xyzf, xyzf + 3 * n), axes(nrmf, nrmf + 3 * n);
  std::vector<float> sqd(n * k, INFINITY);
  std::vector<int32_t> nb(n * k, -1);
  dacpo_err err{};
  dacpo_kdtree* tree = nullptr;
  EXPECT_EQ(dacpo_kdtree_build(xyz.data(), n, &tree, &err), DACPO_OK);
  int32_t idx[k + 1];
  double d2[k + 1];
  for (size_t i = 0; i < n; ++i) {
    const size_t got = dacpo_kdtree_knn(tree, xyz.data() + 3 * i, k + 1, idx, d2);
    for (size_t j = 1; j < got; ++j) {
      sqd[i * k + j - 1] = (float)d2[j];
      nb[i * k + j - 1] = idx[j];
    }
  }
  dacpo_kdtree_free(tree);
  double share = -1.0, copies = -1.0, doubled = -1.0, crossing = -1.0;
  EXPECT_EQ(dacpo_layered_share(xyz.data(),
                                axes.data(),
                                n,
                                nb.data(),
                                sqd.data(),
                                k,
                                &share,
                                &copies,
                                &doubled,
                                &crossing,
                                &err),
            DACPO_OK)
      << err.msg;
  if (copies_out)
    *copies_out = copies;
  if (doubled_out)
    *doubled_out = doubled;
  return share;
}

// % wrong of n points (ground truth gt) oriented by the public API from
// unsigned PCA normals; the run's stats in *stats.
double
orientPoints(const float* xyz,
             const float* gt,
             size_t n,
             dacpo_scan_kind kind,
             uint64_t seed,
             dacpo_stats* stats)
{
  std::vector<float> nrm(3 * n, 0.0f);
  dacpo_params p;
  dacpo_params_init(&p);
  p.estimate_normals = 1;
  p.scan_kind = kind;
  p.seed = seed;
  dacpo_ctx* ctx = nullptr;
  EXPECT_EQ(dacpo_ctx_create(&ctx), DACPO_OK);
  const dacpo_status s = dacpo_orient(ctx, &p, nullptr, nullptr, xyz, nrm.data(), n);
  EXPECT_EQ(s, DACPO_OK) << dacpo_ctx_last_error(ctx);
  *stats = *dacpo_ctx_stats(ctx);
  dacpo_ctx_free(ctx);
  return s == DACPO_OK ? dacpo_score_oriented(gt, nrm.data(), n, nullptr, nullptr)
                       : 100.0;
}

// The scene oriented as above (run seed 1).
double
orientScore(const dacpo_scene& sc, dacpo_scan_kind kind, dacpo_stats* stats)
{
  return orientPoints(sc.xyz, sc.normals, sc.n, kind, 1, stats);
}

} // namespace

TEST(DacpoLayered, FusedRoomShowsCopiesAPlainOneDoesNot)
{
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    GeneratedScene fused(roomParams(100000, 3, seed)), plain(roomParams(100000, 0, seed));
    ASSERT_TRUE(fused.ok && plain.ok);
    double fc = -1.0, pc = -1.0;
    const double f = shareOf(fused.s.xyz, fused.s.normals, fused.s.n, &fc);
    const double p = shareOf(plain.s.xyz, plain.s.normals, plain.s.n, &pc);
    printf("seed %llu: layered share fused %.3f, plain %.3f; copy rate fused %.3f, plain %.3f\n",
           (unsigned long long)seed,
           f,
           p,
           fc,
           pc);
    EXPECT_GE(fc, DACPO_LAYERED_COPIES) << "seed " << seed;
    EXPECT_LT(pc, 0.5 * DACPO_LAYERED_COPIES) << "seed " << seed;
    EXPECT_GE(f, DACPO_LAYERED_SHARE) << "seed " << seed;
    EXPECT_LT(p, 0.25 * DACPO_LAYERED_SHARE) << "seed " << seed;
  }
}

// Whole views off by a few centimetres along the floor's normal (fz_lr_a_n20's
// 2 cm and 0.5 degrees per frame) lay copies 4-5 spacings apart: a point's
// nearest all lie on its own copy, so the pair window of two spacings misses
// them, but most of the floor is doubled within the slab. Here every second
// point of a generated room is lifted by `lift` spacings (its walls slide
// along themselves); a thing resting on a floor covers only a part of it.
// (Through the pipeline this room does not show it: each copy of the floor
// holds half its points, a wall's band then holds more, and the walls, slid
// along themselves, show no copies; fz_lr_a_n20's lowest floor copy stays the
// largest band. Reading every band's doubled share was measured and not kept:
// docs/DESIGN.md, "every one-sided band".)
TEST(DacpoLayered, CopiesWiderThanThePairWindowDoubleTheFloor)
{
  for (uint64_t seed = 1; seed <= 2; ++seed) {
    GeneratedScene plain(roomParams(100000, 0, seed));
    ASSERT_TRUE(plain.ok);
    const size_t n = plain.s.n;
    std::vector<float> xyz(plain.s.xyz, plain.s.xyz + 3 * n);
    const double spacing = 0.0157; // the room's median nearest-neighbour distance
    for (double lift : {4.0, 6.0}) {
      for (size_t i = 1; i < n; i += 2)
        xyz[3 * i + 2] = plain.s.xyz[3 * i + 2] + (float)(lift * spacing);
      double copies = -1.0, doubled = -1.0, pc = -1.0, pd = -1.0;
      shareOf(xyz.data(), plain.s.normals, n, &copies, &doubled);
      shareOf(plain.s.xyz, plain.s.normals, n, &pc, &pd);
      printf("seed %llu, copies %.1f spacings apart: copy rate %.3f, doubled %.3f; plain room "
             "%.3f, %.3f\n",
             (unsigned long long)seed,
             lift,
             copies,
             doubled,
             pc,
             pd);
      EXPECT_GE(doubled, DACPO_LAYERED_DOUBLED) << "seed " << seed << " lift " << lift;
      EXPECT_LT(pd, 0.25 * DACPO_LAYERED_DOUBLED) << "seed " << seed;
    }
  }
}

// Where the floor is hidden (cut out here: furniture, or frames that miss it)
// the fullest band is a wall, which is lower than the room is deep; it lies
// under the scene all the same (the room stands in front of it), so a fused
// room's copies are read on the wall.
TEST(DacpoLayered, CopiesAreReadOnAWallWhenTheFloorIsHidden)
{
  for (uint64_t seed = 1; seed <= 2; ++seed) {
    for (unsigned views : {3u, 0u}) {
      GeneratedScene room(roomParams(100000, views, seed));
      ASSERT_TRUE(room.ok);
      std::vector<float> xyz, nrm;
      for (size_t i = 0; i < room.s.n; ++i) {
        const float* p = room.s.xyz + 3 * i;
        const float* g = room.s.normals + 3 * i;
        if (p[2] < 0.1f && g[2] > 0.9f)
          continue; // the floor
        xyz.insert(xyz.end(), p, p + 3);
        nrm.insert(nrm.end(), g, g + 3);
      }
      double copies = -1.0;
      shareOf(xyz.data(), nrm.data(), xyz.size() / 3, &copies);
      printf("seed %llu, %u views, no floor: copy rate %.3f\n",
             (unsigned long long)seed,
             views,
             copies);
      if (views)
        EXPECT_GE(copies, DACPO_LAYERED_COPIES) << "seed " << seed;
      else
        EXPECT_LT(copies, 0.5 * DACPO_LAYERED_COPIES) << "seed " << seed;
    }
  }
}

// "Nothing lies beneath a floor" is read under the floor's footprint: a lower
// floor beside the room (through a doorway, fz_lr_a_n20's patch 15-20 cm down)
// is not beneath it, a patch under it is. The room's floor comes as two copies
// 4 spacings apart, so the copy rates say whether the band qualified.
TEST(DacpoLayered, OnlyWhatLiesUnderTheFloorCountsAsBeneathIt)
{
  GeneratedScene plain(roomParams(100000, 0, 1));
  ASSERT_TRUE(plain.ok);
  const size_t n = plain.s.n, extra = 4000; // 4 % of the points: above the guard's 2 %
  for (double x0 : {6.5, 2.5}) {              // the room spans x 0-6 m, y 0-5 m
    std::vector<float> xyz(plain.s.xyz, plain.s.xyz + 3 * n);
    std::vector<float> nrm(plain.s.normals, plain.s.normals + 3 * n);
    for (size_t i = 1; i < n; i += 2)
      xyz[3 * i + 2] += (float)(4.0 * 0.0157);
    for (size_t i = 0; i < extra; ++i) { // a 1 m x 1 m patch 15 cm down, facing up
      xyz.insert(xyz.end(),
                 {(float)(x0 + (double)(i % 64) / 64.0), (float)(2.0 + (double)(i / 64) / 64.0), -0.15f});
      nrm.insert(nrm.end(), {0.0f, 0.0f, 1.0f});
    }
    double copies = -1.0, doubled = -1.0;
    shareOf(xyz.data(), nrm.data(), n + extra, &copies, &doubled);
    printf("patch at x %.1f m: copy rate %.3f, doubled %.3f\n", x0, copies, doubled);
    if (x0 > 6.0)
      EXPECT_GE(doubled, DACPO_LAYERED_DOUBLED) << "beside the floor";
    else
      EXPECT_EQ(doubled, 0.0) << "under the floor";
  }
}

// Two sheets facing away from each other are a thin solid's faces, and nothing
// else lies beside them: the test must not call them copies.
TEST(DacpoLayered, TwoSheetsAloneAreNotCopies)
{
  dacpo_scene sc{};
  char msg[256];
  ASSERT_EQ(dacpo_scene_parallel_sheets(1.0, 0.02, 0.01, 0.0, 1, &sc, msg, sizeof(msg)), 0)
      << msg;
  double copies = -1.0;
  EXPECT_EQ(shareOf(sc.xyz, sc.normals, sc.n, &copies), 0.0);
  EXPECT_EQ(copies, 0.0);
  dacpo_scene_free(&sc);
}

TEST(DacpoLayered, BadArgumentsAndTinyClouds)
{
  const double xyz[6] = {0, 0, 0, 1, 0, 0};
  const double axes[6] = {0, 0, 1, 0, 0, 1};
  const float sqd[2] = {1.0f, 1.0f};
  const int32_t nb[2] = {1, 0};
  double share = -1.0, copies = -1.0, doubled = -1.0, crossing = -1.0;
  dacpo_err err{};
  EXPECT_EQ(
      dacpo_layered_share(
          nullptr, axes, 2, nb, sqd, 1, &share, &copies, &doubled, &crossing, &err),
      DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_layered_share(
                xyz, axes, 2, nb, sqd, 1, nullptr, &copies, &doubled, &crossing, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_layered_share(
                xyz, axes, 2, nb, sqd, 1, &share, &copies, nullptr, &crossing, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_layered_share(
                xyz, axes, 2, nb, sqd, 1, &share, &copies, &doubled, &crossing, &err),
            DACPO_OK);
  EXPECT_EQ(share, 0.0);
  EXPECT_EQ(copies, 0.0);
  EXPECT_EQ(doubled, 0.0);
  EXPECT_EQ(crossing, 0.0);
}

// Through the pipeline: AUTO finds the copies and leaves the side cue and the
// two-sheet rule out; given MULTI_VIEW keeps the cue. Measured (run seed 1,
// 100K points, scene seed 2) with blocks grown by hop count: AUTO 7.14 %,
// MULTI_VIEW 30.83 % (the copies faced away from each other and the cue's
// anchors turned whole blocks). Since blocks end at creases: AUTO 9.93 %
// (parts split off at weak crease edges, 16 instead of 5; with
// weak_edge_fraction 0.5: 7.26 %, docs/DESIGN.md), MULTI_VIEW 5.52 %: the cue
// no longer turns blocks here, so only AUTO's error is held. With the copies'
// axes retaken at a larger scale where they turn (4,109 of them): AUTO 7.22 %.
TEST(DacpoLayered, PipelineLeavesTheCueOutOnFusedRooms)
{
  GeneratedScene fused(roomParams(100000, 3, 2));
  ASSERT_TRUE(fused.ok);
  dacpo_stats autos{}, multi{};
  const double wrong_auto = orientScore(fused.s, DACPO_SCAN_AUTO, &autos);
  const double wrong_multi = orientScore(fused.s, DACPO_SCAN_MULTI_VIEW, &multi);
  printf("fused room: AUTO %.2f %% (layered %.3f, sides %g, copy-scale axes %zu), "
         "MULTI_VIEW %.2f %%\n",
         wrong_auto,
         autos.layered_share,
         autos.dipole_sides_used,
         autos.copy_scale_axes,
         wrong_multi);
  EXPECT_EQ(autos.scan_kind, DACPO_SCAN_MULTI_VIEW);
  EXPECT_GE(autos.layered_share, DACPO_LAYERED_SHARE);
  EXPECT_EQ(autos.dipole_sides_used, 0.0);
  EXPECT_GE(autos.layered_copies, DACPO_LAYERED_COPIES);
  EXPECT_EQ(autos.dipole_two_sheet_used, 0.0);
  EXPECT_GT(autos.copy_scale_axes, 0u); // axes that turn with the scale, retaken
  EXPECT_EQ(multi.copy_scale_axes, 0u); // a kind given: no copies' treatment
  EXPECT_EQ(multi.layered_share, 0.0);
  EXPECT_GT(multi.dipole_sides_used, 0.0);
  EXPECT_LE(wrong_auto, 10.5);
}

namespace {

// A small linear congruential stream of uniforms in [0, 1) (seeded per test).
struct Uniform {
  uint64_t st;
  double
  operator()()
  {
    st = st * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(st >> 11) / 9007199254740992.0;
  }
};

// % wrong of xyz (ground truth gt) after orientation from PCA axes (AUTO, seed).
double
orientCopies(const std::vector<float>& xyz, const std::vector<float>& gt, uint64_t seed)
{
  dacpo_stats st{};
  return orientPoints(
      xyz.data(), gt.data(), xyz.size() / 3, DACPO_SCAN_AUTO, seed, &st);
}

// Two copies of one 1 m x 1 m plane (random samples, 2 cm mean spacing), the
// second `gap` spacings above the first and turned by `tilt` degrees about the
// plane's middle line x = 0 (with gap 0 the copies cross there); both face +z.
// Returns % wrong after orientation from PCA axes (AUTO, seed).
double
orientPlaneCopies(double gap, double tilt, uint64_t seed)
{
  const size_t half = 2500;
  const double h = 0.02;
  std::vector<float> xyz, gt;
  Uniform uniform{seed * 0x9E3779B97F4A7C15ull + 1};
  const double a = tilt * M_PI / 180.0;
  for (int copy = 0; copy < 2; ++copy)
    for (size_t i = 0; i < half; ++i) {
      const double x = uniform() - 0.5, y = uniform() - 0.5;
      const double z = copy ? gap * h + x * std::sin(a) : 0.0;
      const double xx = copy ? x * std::cos(a) : x;
      xyz.insert(xyz.end(), {(float)xx, (float)y, (float)z});
      gt.insert(gt.end(), {copy ? (float)-std::sin(a) : 0.0f, 0.0f, copy ? (float)std::cos(a) : 1.0f});
    }
  return orientCopies(xyz, gt, seed);
}

// Two copies of a box corner seen from inside (three 1 m x 1 m faces on the
// planes x = 0, y = 0, z = 0, facing +x, +y, +z; 2,500 random samples each,
// 2 cm mean spacing), the second moved by `gap` spacings along (1, 1, 1) /
// sqrt(3) and turned by `tilt` degrees about the y axis through the box's
// middle. Returns % wrong after orientation from PCA axes (AUTO, seed).
double
orientCornerCopies(double gap, double tilt, uint64_t seed)
{
  const size_t per_face = 2500;
  const double h = 0.02, a = tilt * M_PI / 180.0, c = std::cos(a), s = std::sin(a);
  const double shift = gap * h / std::sqrt(3.0);
  std::vector<float> xyz, gt;
  Uniform uniform{seed * 0x9E3779B97F4A7C15ull + 7};
  for (int copy = 0; copy < 2; ++copy)
    for (int axis = 0; axis < 3; ++axis)
      for (size_t i = 0; i < per_face; ++i) {
        double p[3], n[3] = {0.0, 0.0, 0.0};
        p[axis] = 0.0;
        p[(axis + 1) % 3] = uniform();
        p[(axis + 2) % 3] = uniform();
        n[axis] = 1.0;
        if (copy) { // turn about y through (0.5, 0.5, 0.5), then shift
          const double x = p[0] - 0.5, z = p[2] - 0.5;
          p[0] = c * x + s * z + 0.5 + shift;
          p[1] += shift;
          p[2] = -s * x + c * z + 0.5 + shift;
          const double nx = n[0], nz = n[2];
          n[0] = c * nx + s * nz;
          n[2] = -s * nx + c * nz;
        }
        xyz.insert(xyz.end(), {(float)p[0], (float)p[1], (float)p[2]});
        gt.insert(gt.end(), {(float)n[0], (float)n[1], (float)n[2]});
      }
  return orientCopies(xyz, gt, seed);
}

} // namespace

// Copies of a box corner (a room's corner: each face has the other two on one
// side, so none can be a thin solid's face) keep one orientation: the layered
// test reads the copies on a face with the scene on one side. Measured (seed
// 1): 0.00-0.02 % wrong at every gap and tilt below; with the test skipped
// (MULTI_VIEW given) 40.2-49.7 %, the copies facing away from each other.
TEST(DacpoLayered, TwoCopiesOfABoxCornerKeepOneOrientation)
{
  for (double gap : {0.3, 0.8, 1.5})
    for (double tilt : {0.0, 0.5}) {
      const double wrong = orientCornerCopies(gap, tilt, 1);
      printf("corner copies gap %.1f tilt %.1f: %.2f %% wrong\n", gap, tilt, wrong);
      EXPECT_LE(wrong, 2.0) << "gap " << gap << " tilt " << tilt;
    }
}

// Two copies of a plane that cross (a rotation error between two views tilts
// one against the other; the copies meet along the plane's middle and lie
// `gap` spacings apart at its edges), nothing else in the scene. Two parallel
// copies with nothing else are the same points as the rimless board of
// DacpoThinStructures.SheetsSplitIntoPartsStayFacingAway (faces apart), but a
// thin solid's faces never cross: the layered test's crossing
// (dacpo_sheets_cross.c) calls these copies. Measured (seed 1): 0.00 % wrong
// at 0.3, 0.8 and 1.5 spacings apart; without the crossing (the side cue on
// both sides of the line) 37.60, 44.14, 46.76 %.
TEST(DacpoLayered, TwoCrossingCopiesOfAPlaneKeepOneOrientation)
{
  for (double gap : {0.3, 0.8, 1.5}) {
    const double wrong = orientPlaneCopies(0.0, std::atan(gap * 0.02 / 0.5) * 180.0 / M_PI, 1);
    printf("crossing plane copies, %.1f spacings apart at the edges: %.2f %% wrong\n", gap, wrong);
    EXPECT_LE(wrong, 2.0) << "gap " << gap;
  }
}

namespace {

// % wrong over the points of thin two-sided parts (a point with a ground-truth
// normal facing the other way within `reach` of it: the two faces of a board),
// and their count.
double
thinPartScore(const dacpo_scene& sc, const std::vector<float>& nrm, double reach, size_t* count)
{
  std::vector<double> xyz(sc.xyz, sc.xyz + 3 * sc.n);
  dacpo_err err{};
  dacpo_kdtree* tree = nullptr;
  EXPECT_EQ(dacpo_kdtree_build(xyz.data(), sc.n, &tree, &err), DACPO_OK);
  const size_t k = 32;
  int32_t idx[k];
  double d2[k];
  size_t thin = 0, wrong = 0;
  for (size_t i = 0; i < sc.n; ++i) {
    const float* g = sc.normals + 3 * i;
    const size_t got = dacpo_kdtree_knn(tree, xyz.data() + 3 * i, k, idx, d2);
    bool two_faces = false;
    for (size_t j = 0; j < got && !two_faces; ++j) {
      const float* h = sc.normals + 3 * (size_t)idx[j];
      two_faces = d2[j] <= reach * reach && g[0] * h[0] + g[1] * h[1] + g[2] * h[2] < -0.5f;
    }
    if (!two_faces)
      continue;
    ++thin;
    wrong += g[0] * nrm[3 * i] + g[1] * nrm[3 * i + 1] + g[2] * nrm[3 * i + 2] < 0.0f;
  }
  dacpo_kdtree_free(tree);
  *count = thin;
  return thin ? 100.0 * (double)wrong / (double)thin : 0.0;
}

} // namespace

// A scan of copies holding thin solids: a room seen by five depth cameras,
// 20 mm / 0.5 degrees of pose error per view (scene seed 7, 100K points,
// each view row by row as registered frames concatenated), whose density
// passes for one view (fit 0.55: the two-sheet rule and the side cue are off
// for the whole scan, as for copies) and whose thin parts some cameras saw
// from both sides. Each
// frame's sensor, found from the order, tells the faces apart where the
// geometry cannot: the thin parts' points facing the wrong way (a
// ground-truth normal facing the other way within 3 cm) were 54.86 % of
// 4,654 with windows of consecutive points, 8.06 % with the frames found
// (run seed 1). In the other camera rooms with thin parts it is not yet so:
// docs/DESIGN.md, known limits. (A room fused point by point from random
// views, `fused_views`, has no frames in its order and keeps its boards'
// faces facing one way: 48.56 % of them wrong.)
TEST(DacpoLayered, ThinPartsInAScanOfFramesKeepTheirFacesApart)
{
  dacpo_scene_params sp = GeneratedScene::params(DACPO_SCENE_ROOM, 100000, 7);
  sp.views = 5;
  sp.view_shift = 0.02;
  sp.view_angle = 0.5;
  GeneratedScene cams(sp);
  ASSERT_TRUE(cams.ok);
  std::vector<float> nrm;
  const dacpo_stats st = orientEstimated(cams.s.xyz, cams.s.n, &nrm);
  size_t thin = 0;
  const double wrong = thinPartScore(cams.s, nrm, 0.03, &thin);
  printf("five cameras: %zu thin-part points, %.2f %% of them wrong (two_sheet %g, %zu frame "
         "sensors)\n",
         thin,
         wrong,
         st.dipole_two_sheet_used,
         st.frame_sensors);
  ASSERT_GT(thin, 1000u);
  EXPECT_EQ(st.dipole_two_sheet_used, 0.0); /* no thin-part rule helps */
  EXPECT_GT(st.frame_sensors, 0u);
  EXPECT_LE(wrong, 15.0);
}

namespace {

// Two 1 m x 1 m sheets (2,500 random samples each) in a band's frame: the
// first on y = 0, the second on y = offset + slope (u - pivot), each height
// with Gaussian noise of `sigma` (Box-Muller). Returns the crossing.
double
crossingOf(double offset, double slope, double pivot, double sigma, uint64_t seed)
{
  Uniform uniform{seed * 0x9E3779B97F4A7C15ull + 3};
  std::vector<double> uvy;
  for (int sheet = 0; sheet < 2; ++sheet)
    for (int i = 0; i < 2500; ++i) {
      const double u = uniform() - 0.5, v = uniform() - 0.5;
      const double g = std::sqrt(-2.0 * std::log(1.0 - uniform())) *
                       std::cos(2.0 * M_PI * uniform());
      uvy.insert(uvy.end(),
                 {u, v, (sheet ? offset + slope * (u - pivot) : 0.0) + sigma * g});
    }
  double crossing = -1.0;
  dacpo_err err{};
  EXPECT_EQ(dacpo_sheets_cross(uvy.data(), uvy.size() / 3, 0.007, &crossing, &err),
            DACPO_OK);
  return crossing;
}

} // namespace

// Copies tilted against each other cross along the line where their offset
// passes zero; the cells on either side of it are about half and half.
// Measured (seed 1): 0.485-0.491 for the three tilts clean and the two larger
// with 1 mm noise. Copies 6 mm apart at the edges with 1 mm noise split
// clearly (gap over 5 deviations) in too few cells to say: 0, the cue stays.
TEST(DacpoSheetsCross, TiltedCopiesCrossAlongALine)
{
  const double cases[][2] = {
      {0.006, 0.0}, {0.016, 0.0}, {0.03, 0.0}, {0.016, 0.001}, {0.03, 0.001}};
  for (const auto& c : cases) {
    const double crossing = crossingOf(0.0, c[0] / 0.5, 0.0, c[1], 1);
    printf("copies %.3f m apart at the edges, noise %.3f: crossing %.3f\n",
           c[0],
           c[1],
           crossing);
    EXPECT_GT(crossing, 0.3) << "edge " << c[0] << " noise " << c[1];
    EXPECT_LE(crossing, 0.5);
  }
  EXPECT_EQ(crossingOf(0.0, 0.006 / 0.5, 0.0, 0.001, 1), 0.0);
}

// A thin solid's faces do not cross: a board's two parallel faces (clean and
// noisy), one sheet alone, a wedge whose faces meet at its edge (cells on one
// side of the line only), and copies whose line lies off the band give 0.
TEST(DacpoSheetsCross, FacesThatDoNotCrossGiveNone)
{
  EXPECT_EQ(crossingOf(0.02, 0.0, 0.0, 0.0, 1), 0.0);   // board, 2 cm
  EXPECT_EQ(crossingOf(0.02, 0.0, 0.0, 0.003, 2), 0.0); // noisy board
  EXPECT_EQ(crossingOf(0.0, 0.0, 0.0, 0.001, 3), 0.0);  // one sheet, twice sampled
  EXPECT_EQ(crossingOf(0.0, 0.03, -0.5, 0.0, 4), 0.0);  // wedge from the edge u = -0.5
  EXPECT_EQ(crossingOf(0.0, 0.03, -0.8, 0.0, 5), 0.0);  // would cross beyond the band
}

TEST(DacpoSheetsCross, BadArgumentsAndTinyBands)
{
  dacpo_err err{};
  double crossing = -1.0;
  const double uvy[6] = {0, 0, 0, 1, 1, 0};
  EXPECT_EQ(dacpo_sheets_cross(nullptr, 2, 0.01, &crossing, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_sheets_cross(uvy, 2, 0.01, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_sheets_cross(uvy, 2, 0.01, &crossing, &err), DACPO_OK);
  EXPECT_EQ(crossing, 0.0);
  EXPECT_EQ(dacpo_sheets_cross(uvy, 0, 0.01, &crossing, &err), DACPO_OK);
  EXPECT_EQ(crossing, 0.0);
}
