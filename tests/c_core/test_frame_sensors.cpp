// SPDX-License-Identifier: BSD-3-Clause
// The frames' sensors (sign/dacpo_frame_sensors.c, dacpo_window_sensor in
// input/dacpo_view_kind.c) with known answers: a generated room seen by a few
// depth cameras, its points view by view and each view row by row, as
// registered frames concatenated. The order shows where each camera's points
// end; each window of a frame whose densities place a sensor places it on its
// camera's side (every squarely seen ground-truth normal faces it); the same
// points in a shuffled order, or a room sampled uniformly, give no window a
// sensor. Then the pipeline: a three-camera room whose second camera's walls
// the viewpoint vote turned inside out comes out right.
#include <dacpo/dacpo.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

extern "C" {
#include "dacpo_frame_sensors.h"
#include "dacpo_scene.h"
#include "dacpo_score.h"
#include "dacpo_view_kind.h"
}
#include "scene_fixture.hpp"

namespace {

struct CameraRoom {
  dacpo_scene s{};
  dacpo_scene_view_info info{};
  bool ok = false;
  CameraRoom(size_t n, unsigned views, double shift, double angle, uint64_t seed)
  {
    dacpo_scene_params p;
    dacpo_scene_params_init(&p);
    p.kind = DACPO_SCENE_ROOM;
    p.target_points = n;
    p.seed = seed;
    p.views = views;
    p.view_shift = shift;
    p.view_angle = angle;
    char err[256] = "";
    ok = dacpo_scene_generate_views(&p, &s, &info, err, sizeof(err)) == 0;
    EXPECT_TRUE(ok) << err;
  }
  ~CameraRoom() { dacpo_scene_free(&s); }
  CameraRoom(const CameraRoom&) = delete;
  CameraRoom&
  operator=(const CameraRoom&) = delete;
};

struct Windows {
  dacpo_frame_windows w{};
  size_t found = 0, along = 0;
  Windows(const std::vector<double>& xyz, const std::vector<double>& axes)
  {
    dacpo_err err{};
    EXPECT_EQ(
        dacpo_frame_windows_find(xyz.data(), axes.data(), xyz.size() / 3, 2, &w, &err),
        DACPO_OK)
        << err.msg;
    for (size_t k = 0; k < w.count; ++k) {
      found += w.found[k];
      along += w.along[k];
      EXPECT_LE(w.along[k], w.found[k]) << "window " << k;
    }
  }
  ~Windows() { dacpo_frame_windows_free(&w); }
  Windows(const Windows&) = delete;
  Windows&
  operator=(const Windows&) = delete;
};

// Of window k's points that its sensor sees within 60 degrees of their
// ground-truth normal's axis, those whose normal faces away, and all of them.
void
squarelySeen(const Windows& win,
             size_t k,
             const float* xyz,
             const float* gt,
             size_t* away,
             size_t* all)
{
  const double* v = win.w.sensor + 3 * k;
  *away = *all = 0;
  for (size_t i = win.w.first[k]; i < win.w.end[k]; ++i) {
    double r[3], rr = 0.0, dot = 0.0;
    for (int c = 0; c < 3; ++c) {
      r[c] = v[c] - xyz[3 * i + c];
      rr += r[c] * r[c];
      dot += r[c] * gt[3 * i + c];
    }
    if (std::fabs(dot) < 0.5 * std::sqrt(rr))
      continue;
    ++*all;
    *away += dot < 0.0;
  }
}

// % wrong of scene s oriented by orientEstimated; its normals in *nrm, the
// run's stats in *st.
double
wrongDefault(const dacpo_scene& s, std::vector<float>* nrm, dacpo_stats* st)
{
  *st = orientEstimated(s.xyz, s.n, nrm);
  return dacpo_score_oriented(s.normals, nrm->data(), s.n, nullptr, nullptr);
}

} // namespace

namespace {

// The sensor window [a, b) of room's points places with `camera` (NULL: by
// its own densities alone); its points' axes are their ground truth.
dacpo_window_fit
windowFit(const CameraRoom& room,
          const std::vector<double>& xyz,
          size_t a,
          size_t b,
          const dacpo_window_points* camera)
{
  std::vector<double> axes(room.s.normals + 3 * a, room.s.normals + 3 * b);
  dacpo_window_fit fit{};
  dacpo_err err{};
  EXPECT_EQ(dacpo_window_sensor(
                xyz.data() + 3 * a, axes.data(), b - a, camera, nullptr, &fit, &err),
            DACPO_OK)
      << err.msg;
  return fit;
}

} // namespace

// One camera sees the whole frame: a band of its rows whose densities fit a
// sensor from both sides of its surfaces (a band that sees a wall and a table
// top fits the table's mirror image as well) takes the side of its frame's
// sensor where the frame's window saw the surfaces that tell the two apart
// squarely. Five cameras, 5 mm / 0.1 degrees (scene seeds 2 and 5): each band
// so placed stands on its camera's side. Measured: 6 of 8 tied bands placed,
// 0 of their 17,667 squarely seen points face away.
TEST(DacpoFrameSensors, TiedBandsTakeTheirFramesSide)
{
  size_t tied = 0, placed = 0, away_all = 0, seen_all = 0;
  for (uint64_t seed : {2u, 5u}) {
    CameraRoom room(100000, 5, 0.005, 0.1, seed);
    ASSERT_TRUE(room.ok);
    const std::vector<double> xyz(room.s.xyz, room.s.xyz + 3 * room.s.n);
    for (unsigned v = 0; v < room.info.views; ++v) {
      const size_t a = room.info.view_start[v], b = room.info.view_start[v + 1];
      const dacpo_window_fit frame = windowFit(room, xyz, a, b, nullptr);
      if (!frame.found || !frame.along)
        continue;
      std::vector<double> axes(room.s.normals + 3 * a, room.s.normals + 3 * b);
      const dacpo_window_points camera = {
          xyz.data() + 3 * a, axes.data(), b - a, frame.sensor};
      const size_t bands = (b - a + 2048) / 4096;
      for (size_t j = 0; j < bands; ++j) {
        const size_t first = a + (b - a) * j / bands,
                     end = a + (b - a) * (j + 1) / bands;
        const dacpo_window_fit own = windowFit(room, xyz, first, end, nullptr);
        if (!own.tied)
          continue;
        ++tied;
        EXPECT_FALSE(own.found); /* alone it has no side */
        const dacpo_window_fit fit = windowFit(room, xyz, first, end, &camera);
        if (!fit.found)
          continue;
        ++placed;
        size_t away = 0, all = 0;
        for (size_t i = first; i < end; ++i) {
          double r[3], rr = 0.0, dot = 0.0;
          for (int c = 0; c < 3; ++c) {
            r[c] = fit.sensor[c] - room.s.xyz[3 * i + c];
            rr += r[c] * r[c];
            dot += r[c] * room.s.normals[3 * i + c];
          }
          all += std::fabs(dot) >= 0.5 * std::sqrt(rr);
          away += dot <= -0.5 * std::sqrt(rr);
        }
        EXPECT_LE(away, all / 100) << "seed " << seed << " view " << v << " band " << j;
        away_all += away;
        seen_all += all;
      }
    }
  }
  printf(
      "%zu of %zu tied bands placed from their frame's side; %zu of their %zu squarely "
      "seen points face away\n",
      placed,
      tied,
      away_all,
      seen_all);
  EXPECT_GT(placed, 0u);
}

// Three and five cameras, 5 mm / 0.1 degrees of pose error (scene seed 2):
// every found window lies inside one camera's points and has its sensor on
// that camera's side. Measured: 0 of the squarely seen points face away in
// every found window (15 of 18 and 11 of 20 windows found).
TEST(DacpoFrameSensors, EachFoundWindowStandsOnItsCamerasSide)
{
  for (unsigned views : {3u, 5u}) {
    CameraRoom room(60000, views, 0.005, 0.1, 2);
    ASSERT_TRUE(room.ok);
    const size_t n = room.s.n;
    std::vector<double> xyz(room.s.xyz, room.s.xyz + 3 * n);
    std::vector<double> axes(room.s.normals, room.s.normals + 3 * n);
    Windows win(xyz, axes);
    size_t away_all = 0, seen_all = 0, inside = 0;
    for (size_t k = 0; k < win.w.count; ++k) {
      if (!win.w.found[k])
        continue;
      bool one_view = false;
      for (unsigned v = 0; v < room.info.views; ++v)
        one_view = one_view || (win.w.first[k] >= room.info.view_start[v] &&
                                win.w.end[k] <= room.info.view_start[v + 1]);
      if (!one_view)
        continue;
      ++inside;
      size_t away = 0, all = 0;
      squarelySeen(win, k, room.s.xyz, room.s.normals, &away, &all);
      EXPECT_LE(away, all / 100) << views << " views, window " << k;
      away_all += away;
      seen_all += all;
    }
    printf("%u views: %zu of %zu windows found, %zu inside one view; %zu of their %zu "
           "squarely seen points face away\n",
           views,
           win.found,
           win.w.count,
           inside,
           away_all,
           seen_all);
    EXPECT_EQ(inside, win.found) << views << " views";
    EXPECT_GE(win.found, win.w.count / 3) << views << " views";
  }
}

// Where the points come frame by frame, each frame row by row (the cameras'
// points in raster order), the order shows where each frame ends: across any
// place inside a frame some point lies near one a row before it, across the
// place between two frames next to none. Five cameras (scene seed 2, 60K
// points), and four cameras of 100K points each, whose rows (about 365
// points) are longer than the 256 places looked back before the row length
// was read from the order (no frame found then): every camera's first point
// starts a frame, and no window holds points of two cameras (shuffled, the
// same kind of room shows no frame: below).
TEST(DacpoFrameSensors, TheOrderShowsWhereEachFrameEnds)
{
  struct Case {
    size_t points;
    unsigned views;
  };
  for (const Case& c : {Case{60000, 5}, Case{400000, 4}}) {
    CameraRoom room(c.points, c.views, 0.005, 0.1, 2);
    ASSERT_TRUE(room.ok);
    const size_t n = room.s.n;
    std::vector<double> xyz(room.s.xyz, room.s.xyz + 3 * n);
    std::vector<double> axes(room.s.normals, room.s.normals + 3 * n);
    Windows win(xyz, axes);
    printf("%u cameras, %zu points: %zu frames, %zu windows, %zu found, %zu along the "
           "surfaces\n",
           c.views,
           n,
           win.w.frames,
           win.w.count,
           win.found,
           win.along);
    ASSERT_GE(win.w.frames, c.views);
    for (unsigned v = 1; v < room.info.views; ++v) {
      bool starts = false;
      for (size_t k = 0; k < win.w.count; ++k) {
        starts = starts || win.w.first[k] == room.info.view_start[v];
        EXPECT_FALSE(win.w.first[k] < room.info.view_start[v] &&
                     win.w.end[k] > room.info.view_start[v])
            << "window " << k << " holds points of cameras " << v - 1 << " and " << v;
      }
      EXPECT_TRUE(starts) << "camera " << v;
    }
    EXPECT_GE(win.along, win.w.count / 2);
  }
}

// The order is what finds the frames: the same points shuffled show no frame,
// and a room sampled uniformly gives no window a sensor.
TEST(DacpoFrameSensors, ShuffledPointsOrUniformSamplingFindNone)
{
  CameraRoom room(60000, 3, 0.005, 0.1, 2);
  ASSERT_TRUE(room.ok);
  const size_t n = room.s.n;
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::shuffle(order.begin(), order.end(), std::mt19937_64(7));
  std::vector<double> xyz(3 * n), axes(3 * n);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      xyz[3 * i + c] = room.s.xyz[3 * order[i] + c];
      axes[3 * i + c] = room.s.normals[3 * order[i] + c];
    }
  Windows shuffled(xyz, axes);
  EXPECT_EQ(shuffled.w.frames, 0u);
  EXPECT_EQ(shuffled.found, 0u);

  GeneratedScene uniform(DACPO_SCENE_ROOM, 60000, 2);
  ASSERT_TRUE(uniform.ok);
  std::vector<double> uxyz(uniform.s.xyz, uniform.s.xyz + 3 * uniform.s.n);
  std::vector<double> uaxes(uniform.s.normals, uniform.s.normals + 3 * uniform.s.n);
  Windows even(uxyz, uaxes);
  EXPECT_EQ(even.found, 0u);
}

// Three cameras, 5 mm / 0.1 degrees (scene seed 2, 100K points): with each
// view's points in random order the parts' viewpoint, placed to explain the
// first camera's walls, turned the second camera's inside out (34.02 % wrong
// before the frames' sensors, run seed 1; 2.08 % after, from windows of
// 4,096 consecutive points). Each view row by row, its frames found in the
// order: 0.38 % wrong, 1,114 points turned, 99.62 % with the right sign as
// given.
TEST(DacpoFrameSensors, EachCamerasWallsFaceItsCamera)
{
  CameraRoom room(100000, 3, 0.005, 0.1, 2);
  ASSERT_TRUE(room.ok);
  const size_t n = room.s.n;
  std::vector<float> nrm;
  dacpo_stats st{};
  const double wrong = wrongDefault(room.s, &nrm, &st);
  size_t right_sign = 0;
  for (size_t i = 0; i < n; ++i)
    right_sign += room.s.normals[3 * i] * nrm[3 * i] +
                      room.s.normals[3 * i + 1] * nrm[3 * i + 1] +
                      room.s.normals[3 * i + 2] * nrm[3 * i + 2] >
                  0.0f;
  printf(
      "three cameras: %.2f %% wrong, %.2f %% with the right sign as given; %zu frame "
      "sensors, %zu points turned\n",
      wrong,
      100.0 * (double)right_sign / (double)n,
      st.frame_sensors,
      st.frame_turned);
  EXPECT_GT(st.frame_sensors, 0u);
  EXPECT_LE(wrong, 6.0);
  EXPECT_GE((double)right_sign, 0.94 * (double)n);
}

// A cloud sampled surface by surface (a generated room, its patches one after
// another at one density, as a mesh's faces sampled in order) has no frames.
// A window holding a whole wall and part of the next shows density steps
// that a sensor far outside the room explains (fit 0.80, slope 0.99: one
// window of this room, scene seed 1, 20K points); turned on one window's
// word it made the room 4.28 -> 16.30 % wrong. Both windows holding a point
// must find a sensor: nothing turns.
TEST(DacpoFrameSensors, ASurfaceBySurfaceSampleTurnsNothing)
{
  GeneratedScene room(DACPO_SCENE_ROOM, 20000, 1);
  ASSERT_TRUE(room.ok);
  std::vector<float> nrm;
  dacpo_stats st{};
  const double wrong = wrongDefault(room.s, &nrm, &st);
  printf("surface by surface: %zu frame sensors, %zu points turned, %.2f %% wrong\n",
         st.frame_sensors,
         st.frame_turned,
         wrong);
  EXPECT_EQ(st.frame_turned, 0u);
  EXPECT_LT(wrong, 6.0);
}

// Eight cameras, 5 mm / 0.1 degrees (scene seed 5, 100K points, each view
// row by row): windows of 4,096 consecutive points found 5 sensors, and a
// point needed both windows holding it to find one (6 points turned, 6.42 %
// wrong, run seed 1). With the frames found in the order each frame's bands
// and the whole frame speak for its own points: 11 sensors, 5,685 points
// turned, 0.76 % wrong.
TEST(DacpoFrameSensors, FramesFoundInTheOrderMendWhatTheirCamerasSaw)
{
  CameraRoom room(100000, 8, 0.005, 0.1, 5);
  ASSERT_TRUE(room.ok);
  std::vector<float> nrm;
  dacpo_stats st{};
  const double wrong = wrongDefault(room.s, &nrm, &st);
  printf("eight cameras: %.2f %% wrong; %zu frame sensors, %zu points turned\n",
         wrong,
         st.frame_sensors,
         st.frame_turned);
  EXPECT_GT(st.frame_turned, 3000u);
  EXPECT_LE(wrong, 2.0);
}

// Eight cameras, 5 mm / 0.1 degrees (scene seed 7, 100K points): one frame
// sees only a 10 cm partition's far face, another only a 2 cm board's face
// that the other cameras saw from behind. Flat, each fits its sensor's mirror
// image across the face as well, and no window of the frame places its
// camera, so the parts' vote turned both faces over (23.18 % wrong, run seed
// 1). The mirror image looks at the face through the partition's or the
// board's other face, which other frames saw: the side from which the face is
// not hidden is its camera's (dacpo_free_space.c). Measured: 0.39 %.
TEST(DacpoFrameSensors, AFaceHiddenFromTheMirrorFacesItsCamera)
{
  CameraRoom room(100000, 8, 0.005, 0.1, 7);
  ASSERT_TRUE(room.ok);
  std::vector<float> nrm;
  dacpo_stats st{};
  const double wrong = wrongDefault(room.s, &nrm, &st);
  printf(
      "eight cameras, scene 7: %.2f %% wrong; %zu frame sensors, %zu points turned\n",
      wrong,
      st.frame_sensors,
      st.frame_turned);
  EXPECT_LE(wrong, 5.0);
}
