// SPDX-License-Identifier: BSD-3-Clause
// The relative sign of parts (dacpo_part_sign.c) with known answers: ground-truth
// normals of generated scenes, cut into parts, each part handed over with an
// arbitrary sign (as stages 2-5 leave it). Every part must come back facing the
// same way as the largest one, whatever signs the parts came with, the largest
// part's included. (Not guaranteed in general: the viewpoint candidates lie on
// one side of each sample's normal, so on a scan with a 230-point island the
// relation found changed with the sign the largest part arrived with; see
// docs/DESIGN.md, "the side cue as an absolute sign".)
#include <dacpo/dacpo.h>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

extern "C" {
#include "dacpo_part_sign.h"
}
#include "scene_fixture.hpp"

namespace {

using Scene = GeneratedScene;

// Parts: the four quadrants of the floor plan (x and y halves of the box),
// plus every point above `top` as a fifth, smaller part.
std::vector<int32_t>
quadrants(const dacpo_scene& s, double top)
{
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (size_t i = 0; i < s.n; ++i)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], s.xyz[3 * i + d]);
      hi[d] = std::max(hi[d], s.xyz[3 * i + d]);
    }
  std::vector<int32_t> part(s.n);
  for (size_t i = 0; i < s.n; ++i) {
    const float* p = s.xyz + 3 * i;
    if (p[2] > top)
      part[i] = 4;
    else
      part[i] = (p[0] > 0.5f * (lo[0] + hi[0]) ? 1 : 0) +
                (p[1] > 0.5f * (lo[1] + hi[1]) ? 2 : 0);
  }
  return part;
}

// For every one of the 2^5 sign patterns the parts can arrive with: the sign
// each part ends with relative to the ground truth, which must be the same for
// all parts (one consistent scene) and for all patterns.
void
expectOneRelation(unsigned kind, size_t points, double top)
{
  Scene sc(kind, points, 2);
  ASSERT_TRUE(sc.ok);
  const size_t n = sc.s.n, np = 5;
  const std::vector<int32_t> part = quadrants(sc.s, top);
  std::vector<size_t> size(np, 0);
  for (size_t i = 0; i < n; ++i)
    size[part[i]]++;
  for (size_t c = 0; c < np; ++c)
    ASSERT_GT(size[c], 0u) << "part " << c;
  std::vector<double> xyz(3 * n), nrm(3 * n);
  for (size_t i = 0; i < 3 * n; ++i)
    xyz[i] = sc.s.xyz[i];
  for (unsigned pattern = 0; pattern < (1u << np); ++pattern) {
    SCOPED_TRACE("pattern " + std::to_string(pattern));
    for (size_t i = 0; i < n; ++i) {
      const double given = (pattern >> part[i]) & 1u ? -1.0 : 1.0;
      for (int d = 0; d < 3; ++d)
        nrm[3 * i + d] = given * sc.s.normals[3 * i + d];
    }
    int8_t sign[5];
    double conf[5], score = 0.0;
    dacpo_err err = {DACPO_OK, {0}};
    ASSERT_EQ(dacpo_part_signs(
                  xyz.data(), nrm.data(), n, part.data(), np, sign, conf, &score, &err),
              DACPO_OK)
        << err.msg;
    EXPECT_GE(score, 0.75);
    // the sign each part ends with, against the ground truth
    int first = 0;
    for (size_t c = 0; c < np; ++c) {
      const int given = (pattern >> c) & 1u ? -1 : 1;
      const int final_vs_truth = given * sign[c];
      if (c == 0)
        first = final_vs_truth;
      EXPECT_EQ(final_vs_truth, first) << "part " << c << " (" << size[c] << " points)";
      EXPECT_GT(conf[c], 0.0) << "part " << c;
    }
  }
}

// An open room: floor, walls and furniture, cut into quadrants and the parts
// above 1.2 m (shelf tops, the partition's upper half).
TEST(PartSign, RoomPartsTakeOneRelationWhateverSignsTheyCameWith)
{
  expectOneRelation(DACPO_SCENE_ROOM, 20000, 1.2);
}

// Two rooms joined by a door: the parts straddle the dividing wall.
TEST(PartSign, TwoRoomPartsTakeOneRelationWhateverSignsTheyCameWith)
{
  expectOneRelation(DACPO_SCENE_TWO_ROOMS, 20000, 1.5);
}

// ---- closed parts face outward --------------------------------------------

// Points of four parts with their true normals: 0 a sphere (outward), 1 its
// upper half alone (a cap seen from one side), 2 an open tube with both walls
// (outer wall facing out, inner wall facing the axis), 3 a flat square.
struct Shapes {
  std::vector<double> xyz, nrm;
  std::vector<int32_t> part;
  void
  add(double x, double y, double z, double nx, double ny, double nz, int32_t q)
  {
    xyz.insert(xyz.end(), {x, y, z});
    nrm.insert(nrm.end(), {nx, ny, nz});
    part.push_back(q);
  }
};

Shapes
closedAndOpenShapes()
{
  Shapes s;
  const double golden = 2.399963229728653; // Fibonacci sphere: even spread
  const int m = 1500;
  for (int32_t q = 0; q < 2; ++q) // the sphere's points first, then the cap's
    for (int k = 0; k < m; ++k) {
      const double z = 1.0 - 2.0 * (k + 0.5) / m, r = std::sqrt(1.0 - z * z);
      const double x = r * std::cos(golden * k), y = r * std::sin(golden * k);
      if (q == 0 || z > 0.0)
        s.add(5.0 * q + 0.3 * x, 0.3 * y, 0.3 * z, x, y, z, q);
    }
  for (int k = 0; k < 40; ++k)
    for (int h = 0; h < 20; ++h) {
      const double a = 6.283185307179586 * k / 40, c = std::cos(a), d = std::sin(a);
      const double z = 0.02 * h;
      s.add(10.0 + 0.22 * c, 0.22 * d, z, c, d, 0.0, 2);
      s.add(10.0 + 0.2 * c, 0.2 * d, z, -c, -d, 0.0, 2);
    }
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j)
      s.add(15.0 + 0.02 * i, 0.02 * j, 0.0, 0.0, 0.0, 1.0, 3);
  return s;
}

// The floor the objects stand on (part q): a 50 x 2 m strip below them, the
// scene against which they are object-sized.
void
addFloor(Shapes& s, int32_t q)
{
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 5; ++j)
      s.add(-5.0 + 0.5 * i, -1.0 + 0.5 * j, -1.0, 0.0, 0.0, 1.0, q);
}

TEST(PartSign, ClosedPartsAreToldFromOpenOnesAndSayWhichWayIsOut)
{
  Shapes s = closedAndOpenShapes();
  addFloor(s, 4);
  const size_t n = s.part.size();
  int8_t outward[5];
  dacpo_err err = {DACPO_OK, {0}};
  ASSERT_EQ(dacpo_part_closed_outward(
                s.xyz.data(), s.nrm.data(), n, s.part.data(), 5, outward, &err),
            DACPO_OK)
      << err.msg;
  EXPECT_EQ(outward[0], 1) << "sphere, outward normals";
  EXPECT_EQ(outward[1], 0) << "a cap does not wrap around its centroid";
  EXPECT_EQ(outward[2], 0) << "a tube's two walls face both ways";
  EXPECT_EQ(outward[3], 0) << "flat";
  EXPECT_EQ(outward[4], 0) << "the floor";
  // the same sphere inside out
  for (size_t i = 0; i < n; ++i)
    if (s.part[i] == 0)
      for (int d = 0; d < 3; ++d)
        s.nrm[3 * i + d] = -s.nrm[3 * i + d];
  ASSERT_EQ(dacpo_part_closed_outward(
                s.xyz.data(), s.nrm.data(), n, s.part.data(), 5, outward, &err),
            DACPO_OK);
  EXPECT_EQ(outward[0], -1) << "sphere, inward normals";
  EXPECT_EQ(outward[1], 0);
  // the inward sphere as the whole cloud: a closed room seen from inside
  size_t m = 0;
  while (m < n && s.part[m] == 0)
    ++m;
  ASSERT_EQ(dacpo_part_closed_outward(
                s.xyz.data(), s.nrm.data(), m, s.part.data(), 1, outward, &err),
            DACPO_OK);
  EXPECT_EQ(outward[0], 0) << "a part as large as the scene is not an object";
}

// A free-standing board (both faces sampled, 0.6 x 0.4 m, 2 cm thick, with a
// 1 mm ripple so no offset is exactly 0) is a slab: its faces look away from
// its mid-plane. So is a 10 cm partition seen mostly from one side (a sixth of
// its face points on the other face). A wall patch with a picture on it (its
// back looks into the part, the picture out of it) and a surface seen twice
// 5 mm apart (both copies look the same way) are left alone, and so is a
// surface seen four times whose outer copies face each other (as after a
// two-sheet reading) while the middle ones split, and a floor seen from
// above whose points lie mostly below the middle of their spread.
TEST(PartSign, SlabPartsSayWhichWayIsOut)
{
  Shapes s = closedAndOpenShapes();
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 20; ++j) {
      const double x = 20.0 + 0.02 * i, y = 0.02 * j;
      const double ripple = 0.001 * std::sin(1.7 * i + 2.3 * j);
      s.add(x, y, 0.01 + ripple, 0.0, 0.0, 1.0, 4);   // top face, up
      s.add(x + 0.01, y + 0.01, -0.01 - ripple, 0.0, 0.0, -1.0, 4); // bottom face, down
      s.add(25.0 + x, y, 0.0005 * std::sin(3.1 * i + 0.7 * j), 0.0, 0.0, 1.0, 5); // wall
      if (i >= 10 && i < 20 && j >= 5 && j < 15)
        s.add(25.01 + x, y + 0.01, 0.03, 0.0, 0.0, 1.0, 5); // the picture's front
      const double wobble = 0.001 * std::sin(2.9 * i + 1.3 * j);
      const double px = 60.0 + 0.04 * i, py = 0.04 * j; // a 1.2 x 0.8 m partition:
      s.add(px, py, 0.05 + wobble, 0.0, 0.0, 1.0, 7);   // its face seen all over,
      if (i < 12 && j < 10)                             // a corner of its back
        s.add(px + 0.02, py + 0.02, -0.05 - wobble, 0.0, 0.0, -1.0, 7);
      s.add(100.0 + x, y, wobble, 0.0, 0.0, 1.0, 8); // a surface seen twice
      s.add(100.01 + x, y + 0.01, 0.005 - wobble, 0.0, 0.0, 1.0, 8);
      for (int c = 0; c < 4; ++c) // four times, 1 cm apart, the outer copies
        s.add(120.0 + x + 0.005 * c, y, 0.01 * c + wobble, 0.0, 0.0, c ? -1.0 : 1.0, 9);
      const double low = -0.008 + 0.005 * (0.5 + 0.5 * std::sin(1.3 * i + 3.7 * j));
      s.add(140.0 + x, y, low, 0.0, 0.0, 1.0, 10); // a floor seen from above, its
      const double high = 0.0025 * std::sin(0.9 * i + 2.1 * j);
      if ((i + j) % 5 == 0) // copies' offsets skewed: most low, a few high
        s.add(140.01 + x, y + 0.01, high, 0.0, 0.0, 1.0, 10);
    }
  addFloor(s, 6);
  const size_t n = s.part.size();
  int8_t outward[11];
  dacpo_err err = {DACPO_OK, {0}};
  ASSERT_EQ(dacpo_part_closed_outward(
                s.xyz.data(), s.nrm.data(), n, s.part.data(), 11, outward, &err),
            DACPO_OK)
      << err.msg;
  EXPECT_EQ(outward[4], 1) << "board, faces looking away from each other";
  EXPECT_EQ(outward[5], 0) << "a wall with a picture has one face";
  EXPECT_EQ(outward[3], 0) << "a flat square with one face";
  EXPECT_EQ(outward[0], 1) << "the sphere is still told by the closed test";
  EXPECT_EQ(outward[7], 1) << "a partition seen mostly from one side";
  EXPECT_EQ(outward[8], 0) << "two copies of one surface";
  EXPECT_EQ(outward[9], 0) << "four copies, the outer ones facing each other";
  EXPECT_EQ(outward[10], 0) << "one face, its points mostly below its mid-plane";
  for (size_t i = 0; i < n; ++i)
    if (s.part[i] == 4 || s.part[i] == 5 || s.part[i] == 7 || s.part[i] == 8)
      for (int d = 0; d < 3; ++d)
        s.nrm[3 * i + d] = -s.nrm[3 * i + d];
  ASSERT_EQ(dacpo_part_closed_outward(
                s.xyz.data(), s.nrm.data(), n, s.part.data(), 11, outward, &err),
            DACPO_OK);
  EXPECT_EQ(outward[4], -1) << "board inside out";
  EXPECT_EQ(outward[5], 0) << "the wall the other way round: still one face";
  EXPECT_EQ(outward[7], -1) << "the partition inside out";
  EXPECT_EQ(outward[8], 0) << "the copies the other way round";
}

// A room scanned from inside (floor and four walls, 6 x 5 x 2.6 m: the
// largest part) and a table in it (a 1.6 x 0.9 m top at 0.75 m, four legs of
// 3 cm radius seen from all round) as a part of its own, handed over inside
// out (top facing down, legs facing in) or right. One viewpoint under the top
// explains every point of the inside-out table, one above it only the right
// table's top and the near sides of its legs; a scan is seen from the room's
// free space, outside its objects, so the table must come out facing up
// either way. Known failure (2026-12-05): the viewpoint found is (1.88, 2.55,
// 0.10), beside the table below its top, and the table comes out inside out
// both ways; keeping the viewpoint out of the smaller parts' boxes does not
// change that here (docs/DESIGN.md, known limits). Enable when it holds.
TEST(PartSign, DISABLED_AnObjectInsideTheRoomIsNotSeenFromItsInside)
{
  Shapes s;
  const double X = 6.0, Y = 5.0, H = 2.6, step = 0.05;
  for (double x = 0.0; x <= X; x += step)
    for (double y = 0.0; y <= Y; y += step)
      s.add(x, y, 0.0, 0.0, 0.0, 1.0, 0); // floor
  for (double z = step; z <= H; z += step) {
    for (double x = 0.0; x <= X; x += step) {
      s.add(x, 0.0, z, 0.0, 1.0, 0.0, 0);
      s.add(x, Y, z, 0.0, -1.0, 0.0, 0);
    }
    for (double y = 0.0; y <= Y; y += step) {
      s.add(0.0, y, z, 1.0, 0.0, 0.0, 0);
      s.add(X, y, z, -1.0, 0.0, 0.0, 0);
    }
  }
  const size_t room = s.part.size();
  for (double x = 2.2; x <= 3.8; x += 0.02)
    for (double y = 1.75; y <= 2.65; y += 0.02)
      s.add(x, y, 0.75, 0.0, 0.0, 1.0, 1); // top
  const double kPi = 3.14159265358979323846;
  for (double cx : {2.3, 3.7})
    for (double cy : {1.85, 2.55})
      for (double z = 0.05; z < 0.73; z += 0.02)
        for (int a = 0; a < 12; ++a) {
          const double c = std::cos(2.0 * kPi * a / 12), d = std::sin(2.0 * kPi * a / 12);
          s.add(cx + 0.03 * c, cy + 0.03 * d, z, c, d, 0.0, 1); // legs, outward
        }
  const size_t n = s.part.size();
  for (double given : {-1.0, 1.0}) {
    SCOPED_TRACE(given < 0.0 ? "table handed over inside out" : "table handed over right");
    std::vector<double> nrm = s.nrm;
    for (size_t i = room; i < n; ++i)
      for (int d = 0; d < 3; ++d)
        nrm[3 * i + d] *= given;
    int8_t sign[2] = {0, 0};
    double conf[2] = {0.0, 0.0}, score = 0.0;
    dacpo_err err = {DACPO_OK, {0}};
    ASSERT_EQ(dacpo_part_signs(
                  s.xyz.data(), nrm.data(), n, s.part.data(), 2, sign, conf, &score, &err),
              DACPO_OK)
        << err.msg;
    EXPECT_EQ(sign[0], 1) << "the largest part keeps its sign";
    EXPECT_EQ(sign[1] * given, 1.0) << "the table faces up";
    EXPECT_GT(conf[1], 0.5);
  }
}

// An open room (floor and four walls, 4 x 3 x 2.5 m, normals facing in) at
// `x0` as part q, sampled on a 10 cm grid.
void
addOpenRoom(Shapes& s, double x0, int32_t q)
{
  const double W = 4.0, D = 3.0, H = 2.5, h = 0.1;
  for (double u = 0.05; u < W; u += h) {
    for (double v = 0.05; v < D; v += h)
      s.add(x0 + u, v, 0.0, 0.0, 0.0, 1.0, q);
    for (double v = 0.05; v < H; v += h) {
      s.add(x0 + u, 0.0, v, 0.0, 1.0, 0.0, q);
      s.add(x0 + u, D, v, 0.0, -1.0, 0.0, q);
    }
  }
  for (double u = 0.05; u < D; u += h)
    for (double v = 0.05; v < H; v += h) {
      s.add(x0, u, v, 1.0, 0.0, 0.0, q);
      s.add(x0 + W, u, v, -1.0, 0.0, 0.0, q);
    }
}

// A partition 2 m long and 2 m high, 10 cm thick, both faces sampled (a part
// of its own), standing in an open room of 4 x 3 x 2.5 m: it spans half the
// room's diagonal, more than a closed part may to count as an object, yet
// its faces look away from its mid-plane whatever its size. The room is not
// a slab (its least spread is not thin against the next).
TEST(PartSign, APartitionAsTallAsTheRoomIsASlab)
{
  Shapes s;
  addOpenRoom(s, 0.0, 0);
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) {
      const double y = 0.5 + 0.05 * i, z = 0.05 * j;
      const double ripple = 0.001 * std::sin(1.7 * i + 2.3 * j);
      s.add(1.95 - ripple, y, z, -1.0, 0.0, 0.0, 1);
      s.add(2.05 + ripple, y + 0.025, z + 0.025, 1.0, 0.0, 0.0, 1);
    }
  const size_t n = s.part.size();
  for (double given : {1.0, -1.0}) {
    SCOPED_TRACE(given > 0.0 ? "partition handed over right" : "partition inside out");
    std::vector<double> nrm = s.nrm;
    for (size_t i = 0; i < n; ++i)
      if (s.part[i] == 1)
        for (int d = 0; d < 3; ++d)
          nrm[3 * i + d] *= given;
    int8_t outward[2] = {5, 5};
    dacpo_err err = {DACPO_OK, {0}};
    ASSERT_EQ(dacpo_part_closed_outward(
                  s.xyz.data(), nrm.data(), n, s.part.data(), 2, outward, &err),
              DACPO_OK)
        << err.msg;
    EXPECT_EQ(outward[1], given > 0.0 ? 1 : -1);
    EXPECT_EQ(outward[0], 0) << "the room is neither closed nor a slab";
  }
}

// Two rooms scanned apart (100 m between them) wrap around their centroids
// with their normals facing in, like a closed object turned inside out; in
// the box of the whole cloud each is small. Against the widest part they are
// not objects, and stay with the viewpoint vote; a 30 cm sphere beside the
// second room still is one.
TEST(PartSign, RoomsFarApartAreNotObjects)
{
  Shapes s;
  addOpenRoom(s, 0.0, 0);
  addOpenRoom(s, 100.0, 1);
  const double golden = 2.399963229728653;
  for (int k = 0; k < 600; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / 600, r = std::sqrt(1.0 - z * z);
    const double x = r * std::cos(golden * k), y = r * std::sin(golden * k);
    s.add(106.0 + 0.3 * x, 1.5 + 0.3 * y, 1.0 + 0.3 * z, x, y, z, 2);
  }
  const size_t n = s.part.size();
  int8_t outward[3] = {5, 5, 5};
  dacpo_err err = {DACPO_OK, {0}};
  ASSERT_EQ(dacpo_part_closed_outward(
                s.xyz.data(), s.nrm.data(), n, s.part.data(), 3, outward, &err),
            DACPO_OK)
      << err.msg;
  EXPECT_EQ(outward[0], 0) << "first room";
  EXPECT_EQ(outward[1], 0) << "second room, 100 m away";
  EXPECT_EQ(outward[2], 1) << "a sphere is an object";
}

TEST(PartSign, ClosedPartsRefuseNullInput)
{
  int8_t outward[2] = {5, 5};
  dacpo_err err = {DACPO_OK, {0}};
  EXPECT_EQ(dacpo_part_closed_outward(nullptr, nullptr, 0, nullptr, 0, nullptr, &err),
            DACPO_OK);
  EXPECT_EQ(dacpo_part_closed_outward(nullptr, nullptr, 3, nullptr, 2, outward, &err),
            DACPO_ERR_INVALID_ARGUMENT);
}

} // namespace
