// SPDX-License-Identifier: BSD-3-Clause
// Tests of the synthetic scene generator, the orientation score and the PLY
// reader/writer in wrappers/support (dacpo_scene.c, dacpo_ply.c).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <unistd.h>
#include <vector>

extern "C" {
#include "dacpo_ply.h"
#include "dacpo_scene.h"
}

namespace {

// Owns a generated scene; fails the test when generation fails.
struct Scene {
  dacpo_scene s{};
  Scene(unsigned kind,
        size_t n,
        uint64_t seed = 1,
        double noise = 0.0,
        size_t downsample = 0)
  {
    dacpo_scene_params p;
    dacpo_scene_params_init(&p);
    p.kind = kind;
    p.target_points = n;
    p.seed = seed;
    p.noise_sigma = noise;
    p.downsample_to = downsample;
    char err[256];
    const int rc = dacpo_scene_generate(&p, &s, err, sizeof(err));
    EXPECT_EQ(rc, 0) << err;
  }
  ~Scene() { dacpo_scene_free(&s); }
  Scene(const Scene&) = delete;
  Scene&
  operator=(const Scene&) = delete;
  const float*
  p(size_t i) const
  {
    return s.xyz + 3 * i;
  }
  const float*
  n(size_t i) const
  {
    return s.normals + 3 * i;
  }
};

std::string
TempPath(const std::string& name)
{
  return testing::TempDir() + "dacpo_scene_" + std::to_string(getpid()) + "_" + name;
}

void
WriteBytes(const std::string& path, const void* data, size_t len)
{
  FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  const size_t written = len > 0 ? std::fwrite(data, 1, len, f) : 0;
  std::fclose(f);
  ASSERT_EQ(written, len);
}

std::vector<unsigned char>
ReadBytes(const std::string& path)
{
  std::vector<unsigned char> v;
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f)
    return v;
  int c;
  while ((c = std::fgetc(f)) != EOF)
    v.push_back(static_cast<unsigned char>(c));
  std::fclose(f);
  return v;
}

double
Dot(const float* a, const float* b)
{
  return double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
}

double
Dist2(const float* a, const float* b)
{
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

} // namespace

// ---------------------------------------------------------------------------
// Generator.

TEST(DacpoScene, PointCountsAreExact)
{
  for (unsigned kind = 0; kind < DACPO_SCENE_KIND_COUNT; ++kind) {
    for (size_t n : {size_t(1), size_t(7), size_t(1000), size_t(12345)}) {
      Scene sc(kind, n);
      ASSERT_EQ(sc.s.n, n) << dacpo_scene_kind_name(kind);
      ASSERT_GT(sc.s.num_parts, 0u);
      ASSERT_GT(sc.s.num_objects, 0u);
      for (size_t i = 0; i < sc.s.n; ++i) {
        ASSERT_GE(sc.s.part[i], 0);
        ASSERT_LT(size_t(sc.s.part[i]), sc.s.num_parts);
      }
      for (size_t j = 0; j < sc.s.num_parts; ++j) {
        ASSERT_GE(sc.s.part_object[j], 0);
        ASSERT_LT(size_t(sc.s.part_object[j]), sc.s.num_objects);
      }
      for (size_t j = 0; j < sc.s.num_objects; ++j)
        ASSERT_NE(sc.s.object_name[j], nullptr);
    }
  }
}

TEST(DacpoScene, AllNormalsAreUnit)
{
  for (unsigned kind = 0; kind < DACPO_SCENE_KIND_COUNT; ++kind) {
    Scene sc(kind, 20000, 3, 0.004);
    for (size_t i = 0; i < sc.s.n; ++i)
      ASSERT_NEAR(Dot(sc.n(i), sc.n(i)), 1.0, 1e-5)
          << dacpo_scene_kind_name(kind) << " point " << i;
  }
}

TEST(DacpoScene, KindNamesRoundTrip)
{
  for (unsigned kind = 0; kind < DACPO_SCENE_KIND_COUNT; ++kind) {
    unsigned back = 99;
    ASSERT_NE(dacpo_scene_kind_name(kind), nullptr);
    ASSERT_EQ(dacpo_scene_kind_from_name(dacpo_scene_kind_name(kind), &back), 0);
    EXPECT_EQ(back, kind);
  }
  unsigned k;
  EXPECT_EQ(dacpo_scene_kind_name(DACPO_SCENE_KIND_COUNT), nullptr);
  EXPECT_NE(dacpo_scene_kind_from_name("ceiling", &k), 0);
  EXPECT_NE(dacpo_scene_kind_from_name(nullptr, &k), 0);
}

TEST(DacpoScene, SameSeedGivesIdenticalBytes)
{
  Scene a(DACPO_SCENE_ROOM, 50000, 42, 0.008, 20000);
  Scene b(DACPO_SCENE_ROOM, 50000, 42, 0.008, 20000);
  ASSERT_EQ(a.s.n, b.s.n);
  EXPECT_EQ(std::memcmp(a.s.xyz, b.s.xyz, 3 * a.s.n * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(a.s.normals, b.s.normals, 3 * a.s.n * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(a.s.part, b.s.part, a.s.n * sizeof(int32_t)), 0);
}

TEST(DacpoScene, DifferentSeedGivesDifferentPoints)
{
  Scene a(DACPO_SCENE_ROOM, 50000, 1);
  Scene b(DACPO_SCENE_ROOM, 50000, 2);
  ASSERT_EQ(a.s.n, b.s.n);
  size_t same = 0;
  for (size_t i = 0; i < a.s.n; ++i)
    same += Dist2(a.p(i), b.p(i)) == 0.0;
  EXPECT_LT(same, a.s.n / 100);
}

TEST(DacpoScene, InvalidParametersAreRejected)
{
  dacpo_scene_params p;
  dacpo_scene s;
  char err[256];
  EXPECT_EQ(dacpo_scene_generate(nullptr, &s, err, sizeof(err)), -1);
  EXPECT_GT(std::strlen(err), 0u);
  dacpo_scene_params_init(&p);
  EXPECT_EQ(dacpo_scene_generate(&p, nullptr, err, sizeof(err)), -1);

  dacpo_scene_params_init(&p);
  p.kind = DACPO_SCENE_KIND_COUNT;
  EXPECT_EQ(dacpo_scene_generate(&p, &s, err, sizeof(err)), -1);
  EXPECT_NE(std::string(err).find("kind"), std::string::npos) << err;
  EXPECT_EQ(s.n, 0u);
  EXPECT_EQ(s.xyz, nullptr);

  dacpo_scene_params_init(&p);
  p.target_points = 0;
  EXPECT_EQ(dacpo_scene_generate(&p, &s, err, sizeof(err)), -1);

  dacpo_scene_params_init(&p);
  p.noise_sigma = -0.1;
  EXPECT_EQ(dacpo_scene_generate(&p, &s, err, sizeof(err)), -1);
  p.noise_sigma = NAN;
  EXPECT_EQ(dacpo_scene_generate(&p, &s, err, sizeof(err)), -1);
  p.noise_sigma = INFINITY;
  EXPECT_EQ(dacpo_scene_generate(&p, &s, err, sizeof(err)), -1);

  dacpo_scene_params_init(&p);
  p.target_points = 100;
  p.downsample_to = 101;
  EXPECT_EQ(dacpo_scene_generate(&p, &s, err, sizeof(err)), -1);
  EXPECT_NE(std::string(err).find("downsample_to"), std::string::npos) << err;
  // NULL error buffer is fine too.
  EXPECT_EQ(dacpo_scene_generate(&p, &s, nullptr, 0), -1);
  dacpo_scene_free(&s);
  dacpo_scene_free(nullptr);
}

TEST(DacpoScene, NoiseSigmaMatchesRequest)
{
  // Plane z = 0, normal +z: the noise's normal component is sigma N(0,1) u_z
  // with u uniform on the sphere, so its standard deviation is sigma / sqrt(3);
  // the displacement's RMS length is sigma and its mean length is
  // sigma sqrt(2/pi) (paper: 0.004 -> mean 0.0032).
  for (double sigma : {0.004, 0.008}) {
    Scene noisy(DACPO_SCENE_PLANE, 200000, 7, sigma);
    Scene clean(DACPO_SCENE_PLANE, 200000, 7, 0.0);
    ASSERT_EQ(noisy.s.n, clean.s.n);
    double sz = 0.0, sd2 = 0.0, sd = 0.0;
    for (size_t i = 0; i < noisy.s.n; ++i) {
      const double z = noisy.p(i)[2];
      sz += z * z;
      const double d2 = Dist2(noisy.p(i), clean.p(i));
      sd2 += d2;
      sd += std::sqrt(d2);
      ASSERT_EQ(std::memcmp(noisy.n(i), clean.n(i), 3 * sizeof(float)), 0);
    }
    const double n = double(noisy.s.n);
    const double std_z = std::sqrt(sz / n);
    EXPECT_NEAR(std_z, sigma / std::sqrt(3.0), 0.1 * sigma / std::sqrt(3.0));
    EXPECT_NEAR(std::sqrt(sd2 / n), sigma, 0.02 * sigma);
    EXPECT_NEAR(sd / n, sigma * std::sqrt(2.0 / M_PI), 0.02 * sigma);
  }
}

TEST(DacpoScene, DownsampleKeepsExactCountInOrder)
{
  Scene full(DACPO_SCENE_ROOM, 100000, 5);
  Scene down(DACPO_SCENE_ROOM, 100000, 5, 0.0, 10000);
  ASSERT_EQ(down.s.n, 10000u);
  // Same geometry stream: the downsampled cloud is a subsequence of the full one.
  size_t j = 0;
  for (size_t i = 0; i < down.s.n; ++i) {
    while (j < full.s.n && std::memcmp(full.p(j), down.p(i), 3 * sizeof(float)) != 0)
      ++j;
    ASSERT_LT(j, full.s.n) << "downsampled point " << i << " not found in order";
    EXPECT_EQ(full.s.part[j], down.s.part[i]);
    ++j;
  }
  // Spread over the whole cloud, not a prefix.
  EXPECT_GT(j, full.s.n - full.s.n / 100);
  // downsample_to == target_points keeps everything.
  Scene all(DACPO_SCENE_PLANE, 1000, 5, 0.0, 1000);
  Scene ref(DACPO_SCENE_PLANE, 1000, 5);
  ASSERT_EQ(all.s.n, 1000u);
  EXPECT_EQ(std::memcmp(all.s.xyz, ref.s.xyz, 3000 * sizeof(float)), 0);
}

TEST(DacpoScene, RoomIsOpenWithInwardWalls)
{
  const double H = DACPO_SCENE_ROOM_HEIGHT;
  const double X = DACPO_SCENE_ROOM_SIZE_X, Y = DACPO_SCENE_ROOM_SIZE_Y;
  Scene sc(DACPO_SCENE_ROOM, 200000, 11);
  size_t near_top = 0, downward_high = 0;
  for (size_t i = 0; i < sc.s.n; ++i) {
    const float* p = sc.p(i);
    const float* n = sc.n(i);
    ASSERT_LE(p[2], H + 1e-5);
    ASSERT_GE(p[2], -1e-6);
    near_top += p[2] > H - 0.05;
    // No ceiling: nothing above the tallest furniture (1.82 m) faces down.
    downward_high += p[2] > 1.9 && n[2] < -0.5;
    // Every normal leads into the room's interior (open at the top).
    const double q[3] = {p[0] + 0.005 * n[0], p[1] + 0.005 * n[1], p[2] + 0.005 * n[2]};
    ASSERT_TRUE(q[0] > 0 && q[0] < X && q[1] > 0 && q[1] < Y && q[2] > 0)
        << "point " << i << " (" << p[0] << ", " << p[1] << ", " << p[2] << ")";
    // Walls: only the inner face is sampled.
    if (p[0] < 1e-6) {
      ASSERT_GT(n[0], 0.99f);
    }
    if (p[0] > X - 1e-6) {
      ASSERT_LT(n[0], -0.99f);
    }
    if (p[1] < 1e-6) {
      ASSERT_GT(n[1], 0.99f);
    }
    if (p[1] > Y - 1e-6) {
      ASSERT_LT(n[1], -0.99f);
    }
  }
  EXPECT_GT(near_top, 1000u); // walls reach the top edge
  EXPECT_EQ(downward_high, 0u);
  // Door opening in the south wall (x in [4.5, 5.4], z < 2.05): empty.
  for (size_t i = 0; i < sc.s.n; ++i) {
    const float* p = sc.p(i);
    ASSERT_FALSE(p[1] < 1e-6 && p[0] > 4.5 && p[0] < 5.4 && p[2] < 2.05 && p[2] > 1e-6);
  }
  // Furniture is there: table, chairs, bookshelf, bin, partition, screen, cabinet.
  EXPECT_GE(sc.s.num_objects, 9u);
}

TEST(DacpoScene, ThinBoardFacesAreOpposite)
{
  Scene sc(DACPO_SCENE_BOARD, 20000, 2);
  ASSERT_EQ(sc.s.num_parts, 6u);
  size_t top = 0, bottom = 0;
  for (size_t i = 0; i < sc.s.n; ++i) {
    if (sc.s.part[i] == 4) {
      ++top;
      EXPECT_FLOAT_EQ(sc.n(i)[2], 1.0f);
      EXPECT_NEAR(sc.p(i)[2], 0.01, 1e-6);
    }
    if (sc.s.part[i] == 5) {
      ++bottom;
      EXPECT_FLOAT_EQ(sc.n(i)[2], -1.0f);
      EXPECT_NEAR(sc.p(i)[2], -0.01, 1e-6);
    }
    // All six faces: normals point out of the board.
    const float* p = sc.p(i);
    const float* n = sc.n(i);
    const double q[3] = {p[0] + 0.001 * n[0], p[1] + 0.001 * n[1], p[2] + 0.001 * n[2]};
    ASSERT_TRUE(std::fabs(q[0]) > 0.5 || std::fabs(q[1]) > 0.3 ||
                std::fabs(q[2]) > 0.01);
  }
  // Equal areas, equal shares (largest remainder: within one point).
  EXPECT_LE(top > bottom ? top - bottom : bottom - top, 1u);
  EXPECT_NEAR(double(top) / sc.s.n, 0.6 / (2 * 0.6 + 2 * 0.02 * 1.6), 0.001);
}

TEST(DacpoScene, CurvedSurfacesHaveRadialNormals)
{
  Scene sphere(DACPO_SCENE_SPHERE, 5000, 1);
  for (size_t i = 0; i < sphere.s.n; ++i) {
    ASSERT_NEAR(Dot(sphere.p(i), sphere.p(i)), 1.0, 1e-5);
    ASSERT_NEAR(Dot(sphere.p(i), sphere.n(i)), 1.0, 1e-5);
  }
  Scene half(DACPO_SCENE_HALF_CYLINDER, 5000, 1);
  for (size_t i = 0; i < half.s.n; ++i) {
    const float* p = half.p(i);
    const float* n = half.n(i);
    ASSERT_GE(p[2], -1e-6);
    ASSERT_NEAR(p[0] * p[0] + p[2] * p[2], 1.0, 1e-5);
    ASSERT_NEAR(p[0] * n[0] + p[2] * n[2], 1.0, 1e-5);
    ASSERT_EQ(n[1], 0.0f);
    ASSERT_LE(std::fabs(p[1]), 1.0 + 1e-6);
  }
}

// Nearest neighbours on one connected smooth or corner-joined surface must not
// have opposite ground-truth normals (brute force, small clouds).
TEST(DacpoScene, NeighbouringNormalsAreConsistent)
{
  for (unsigned kind : {unsigned(DACPO_SCENE_SPHERE),
                        unsigned(DACPO_SCENE_HALF_CYLINDER),
                        unsigned(DACPO_SCENE_S_SHEET),
                        unsigned(DACPO_SCENE_BOX_OPEN),
                        unsigned(DACPO_SCENE_PLANE)}) {
    Scene sc(kind, 3000, 9);
    for (size_t i = 0; i < sc.s.n; ++i) {
      size_t best = i;
      double bd = 1e30;
      for (size_t j = 0; j < sc.s.n; ++j) {
        if (j == i)
          continue;
        const double d = Dist2(sc.p(i), sc.p(j));
        if (d < bd) {
          bd = d;
          best = j;
        }
      }
      ASSERT_GT(Dot(sc.n(i), sc.n(best)), -1e-6)
          << dacpo_scene_kind_name(kind) << " point " << i;
    }
  }
}

TEST(DacpoScene, SSheetJointIsConsistent)
{
  Scene sc(DACPO_SCENE_S_SHEET, 40000, 4);
  ASSERT_EQ(sc.s.num_parts, 2u);
  size_t near_joint = 0;
  for (size_t i = 0; i < sc.s.n; ++i) {
    const float* p = sc.p(i);
    // Both arcs near the joint (x, z) = (0, 1) have normals close to +z.
    if (std::fabs(p[2] - 1.0) < 0.02 && std::fabs(p[0]) < 0.15) {
      ++near_joint;
      EXPECT_GT(sc.n(i)[2], 0.9f);
    }
  }
  EXPECT_GT(near_joint, 100u);
}

TEST(DacpoScene, TwoRoomsShareAWallWithADoor)
{
  Scene sc(DACPO_SCENE_TWO_ROOMS, 100000, 8);
  size_t face_a = 0, face_b = 0, door_floor = 0;
  for (size_t i = 0; i < sc.s.n; ++i) {
    const float* p = sc.p(i);
    const float* n = sc.n(i);
    if (std::fabs(p[0] - 4.0f) < 1e-6 && n[0] != 0.0f) {
      ++face_a;
      ASSERT_FLOAT_EQ(n[0], -1.0f); // faces room A
    }
    if (std::fabs(p[0] - 4.1f) < 1e-6 && n[0] != 0.0f) {
      ++face_b;
      ASSERT_FLOAT_EQ(n[0], 1.0f); // faces room B
    }
    // Door y in [1.0, 1.9], z in [0, 2.0]: no points strictly inside.
    ASSERT_FALSE(p[0] > 3.99 && p[0] < 4.11 && p[1] > 1.0001 && p[1] < 1.8999 &&
                 p[2] > 1e-4 && p[2] < 1.9999)
        << "point in the door at " << p[0] << ", " << p[1] << ", " << p[2];
    door_floor += p[2] == 0.0f && p[0] > 4.0f && p[0] < 4.1f;
  }
  EXPECT_GT(face_a, 1000u);
  EXPECT_NEAR(double(face_a), double(face_b), 0.1 * face_a);
  EXPECT_GT(door_floor, 0u); // the floor continues through the door
}

// The building's geometry, face by face: walls between a room and the corridor
// are sampled on both sides (normals into the room / the corridor), no point
// stands in a door, the floor runs on through every door.
TEST(DacpoScene, BuildingRoomsOpenOntoTheCorridor)
{
  Scene sc(DACPO_SCENE_BUILDING, 200000, 2);
  ASSERT_EQ(sc.s.num_objects, 7u); // six rooms and the corridor
  const double W = 4.0, T = 0.1, C = 2.0;
  size_t corridor_face = 0, room_face = 0, door_floor = 0;
  for (size_t i = 0; i < sc.s.n; ++i) {
    const float* p = sc.p(i);
    const float* n = sc.n(i);
    ASSERT_GE(p[2], 0.0f);
    ASSERT_LE(p[2], 2.6f + 1e-5f);
    ASSERT_TRUE(p[0] >= T - 1e-5 && p[0] <= 3 * (W + T) + 1e-5) << p[0];
    if (std::fabs(p[1] - C) < 1e-5 && n[1] != 0.0f) { // corridor side, north slab
      ++corridor_face;
      ASSERT_FLOAT_EQ(n[1], -1.0f);
    }
    if (std::fabs(p[1] - (C + T)) < 1e-5 && n[1] != 0.0f) { // room side
      ++room_face;
      ASSERT_FLOAT_EQ(n[1], 1.0f);
    }
    // Doors: x in [i (W + T) + T + 1.55, ... + 2.45], z < 2: empty across both slabs.
    for (int r = 0; r < 3; ++r) {
      const double d0 = r * (W + T) + T + 0.5 * W - 0.45;
      const bool in_door = p[0] > d0 + 1e-4 && p[0] < d0 + 0.9 - 1e-4 && p[2] > 1e-4 &&
                           p[2] < 2.0 - 1e-4;
      const bool in_slab = (p[1] > C + 1e-4 && p[1] < C + T - 1e-4) ||
                           (p[1] > -T + 1e-4 && p[1] < -1e-4);
      ASSERT_FALSE(in_door && in_slab) << "point in a door at " << p[0] << ", " << p[1];
      door_floor += in_slab && p[2] == 0.0f && p[0] > d0 && p[0] < d0 + 0.9;
    }
  }
  EXPECT_GT(corridor_face, 500u);
  EXPECT_NEAR(double(corridor_face), double(room_face), 0.15 * room_face);
  EXPECT_GT(door_floor, 0u);
}

TEST(DacpoScene, MillionPointsAreFast)
{
  Scene sc(DACPO_SCENE_ROOM, 1000000, 1, 0.004, 500000);
  EXPECT_EQ(sc.s.n, 500000u);
}

// ---------------------------------------------------------------------------
// Sign scrambling and the score.

TEST(DacpoScore, IdenticalAndGloballyFlippedScoreZero)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 10000, 1);
  size_t wrong = 99;
  EXPECT_EQ(dacpo_score_oriented(sc.s.normals, sc.s.normals, sc.s.n, nullptr, &wrong),
            0.0);
  EXPECT_EQ(wrong, 0u);
  std::vector<float> flipped(3 * sc.s.n);
  EXPECT_EQ(dacpo_scene_scramble_signs(&sc.s, flipped.data(), 3, 1.0), sc.s.n);
  EXPECT_EQ(dacpo_score_oriented(sc.s.normals, flipped.data(), sc.s.n, nullptr, &wrong),
            0.0);
  EXPECT_EQ(wrong, 0u);
}

TEST(DacpoScore, PartialFlipsAreCounted)
{
  Scene sc(DACPO_SCENE_ROOM, 10000, 1);
  std::vector<float> pred(3 * sc.s.n);
  size_t wrong = 0;
  EXPECT_EQ(dacpo_scene_scramble_signs(&sc.s, pred.data(), 5, 0.3), 3000u);
  EXPECT_DOUBLE_EQ(
      dacpo_score_oriented(sc.s.normals, pred.data(), sc.s.n, nullptr, &wrong), 30.0);
  EXPECT_EQ(wrong, 3000u);
  // 70 % flipped is 30 % after the free global sign.
  EXPECT_EQ(dacpo_scene_scramble_signs(&sc.s, pred.data(), 5, 0.7), 7000u);
  EXPECT_DOUBLE_EQ(
      dacpo_score_oriented(sc.s.normals, pred.data(), sc.s.n, nullptr, &wrong), 30.0);
  // The flips are spread, not a prefix.
  size_t first_half = 0;
  for (size_t i = 0; i < sc.s.n / 2; ++i)
    first_half += Dot(pred.data() + 3 * i, sc.n(i)) < 0;
  EXPECT_NEAR(double(first_half), 3500.0, 250.0);
}

TEST(DacpoScore, ScrambleWorksInPlaceAndClamps)
{
  std::vector<float> a(300), b(300);
  for (size_t i = 0; i < 100; ++i) {
    a[3 * i] = 0.0f;
    a[3 * i + 1] = 0.0f;
    a[3 * i + 2] = 1.0f;
  }
  b = a;
  EXPECT_EQ(dacpo_scramble_signs(b.data(), b.data(), 100, 1, 0.25), 25u);
  size_t neg = 0;
  for (size_t i = 0; i < 100; ++i)
    neg += b[3 * i + 2] < 0;
  EXPECT_EQ(neg, 25u);
  EXPECT_EQ(dacpo_scramble_signs(a.data(), b.data(), 100, 1, -1.0), 0u);
  EXPECT_EQ(dacpo_scramble_signs(a.data(), b.data(), 100, 1, 7.0), 100u);
  EXPECT_EQ(dacpo_scramble_signs(a.data(), b.data(), 100, 1, NAN), 0u);
  EXPECT_EQ(dacpo_scramble_signs(nullptr, b.data(), 100, 1, 0.5), 0u);
}

TEST(DacpoScore, ComponentLabelsGetOneSignEach)
{
  Scene sc(DACPO_SCENE_BOX_OPEN, 10000, 2);
  const size_t n = sc.s.n;
  std::vector<float> pred(sc.s.normals, sc.s.normals + 3 * n);
  // Flip the floor and one wall completely: with per-part signs nothing is
  // wrong, with one global sign those parts are.
  size_t flipped = 0;
  for (size_t i = 0; i < n; ++i) {
    if (sc.s.part[i] == 0 || sc.s.part[i] == 2) {
      for (int k = 0; k < 3; ++k)
        pred[3 * i + k] = -pred[3 * i + k];
      ++flipped;
    }
  }
  ASSERT_LT(flipped, n / 2);
  size_t wrong = 0;
  EXPECT_DOUBLE_EQ(
      dacpo_score_oriented(sc.s.normals, pred.data(), n, sc.s.part, &wrong), 0.0);
  EXPECT_DOUBLE_EQ(dacpo_score_oriented(sc.s.normals, pred.data(), n, nullptr, &wrong),
                   100.0 * flipped / n);

  // Two labels: 20 % of A wrong, 80 % of B wrong -> 20 % of all.
  std::vector<int32_t> label(n);
  for (size_t i = 0; i < n; ++i)
    label[i] = i < n / 2 ? 0 : 1;
  std::vector<float> gt(3 * n, 0.0f), p2(3 * n, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    gt[3 * i] = 1.0f;
    const size_t local = i < n / 2 ? i : i - n / 2;
    const bool bad = i < n / 2 ? local % 5 == 0 : local % 5 != 0;
    p2[3 * i] = bad ? -0.5f : 0.5f; // not unit on purpose: only the sign matters
  }
  EXPECT_NEAR(
      dacpo_score_oriented(gt.data(), p2.data(), n, label.data(), &wrong), 20.0, 0.05);
  // Sparse, negative labels take the sorting path and agree.
  std::vector<int32_t> sparse(n);
  for (size_t i = 0; i < n; ++i)
    sparse[i] = label[i] == 0 ? -2000000000 : 2000000000;
  size_t wrong_sparse = 0;
  EXPECT_DOUBLE_EQ(
      dacpo_score_oriented(gt.data(), p2.data(), n, sparse.data(), &wrong_sparse),
      dacpo_score_oriented(gt.data(), p2.data(), n, label.data(), &wrong));
  EXPECT_EQ(wrong, wrong_sparse);
}

TEST(DacpoScore, UndecidedAndBadArguments)
{
  const float gt[6] = {0, 0, 1, 0, 0, 1};
  const float pred[6] = {0, 0, 1, 1, 0, 0}; // second is perpendicular
  const float nanp[6] = {0, 0, 1, NAN, 0, 0};
  size_t wrong = 0;
  EXPECT_DOUBLE_EQ(dacpo_score_oriented(gt, pred, 2, nullptr, &wrong), 50.0);
  EXPECT_EQ(wrong, 1u);
  EXPECT_DOUBLE_EQ(dacpo_score_oriented(gt, nanp, 2, nullptr, &wrong), 50.0);
  EXPECT_EQ(dacpo_score_oriented(nullptr, pred, 2, nullptr, &wrong), -1.0);
  EXPECT_EQ(dacpo_score_oriented(gt, nullptr, 2, nullptr, &wrong), -1.0);
  EXPECT_EQ(dacpo_score_oriented(nullptr, nullptr, 0, nullptr, &wrong), 0.0);
  EXPECT_EQ(wrong, 0u);
}

// ---------------------------------------------------------------------------
// PLY.

TEST(DacpoPly, WriteReadRoundTripIsBitExact)
{
  Scene sc(DACPO_SCENE_ROOM, 30000, 6, 0.004);
  const std::string path = TempPath("roundtrip.ply");
  char err[256];
  ASSERT_EQ(dacpo_ply_write(path.c_str(),
                            sc.s.xyz,
                            sc.s.normals,
                            sc.s.n,
                            "line one\nline two",
                            err,
                            sizeof(err)),
            DACPO_PLY_OK)
      << err;
  std::vector<unsigned char> bytes = ReadBytes(path);
  const std::string head(bytes.begin(), bytes.begin() + 200);
  EXPECT_EQ(head.rfind("ply\nformat binary_little_endian 1.0\ncomment line one\n"
                       "comment line two\nelement vertex 30000\n",
                       0),
            0u)
      << head;
  dacpo_ply_cloud c;
  ASSERT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK) << err;
  ASSERT_EQ(c.n, sc.s.n);
  ASSERT_NE(c.normals, nullptr);
  EXPECT_EQ(std::memcmp(c.xyz, sc.s.xyz, 3 * c.n * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(c.normals, sc.s.normals, 3 * c.n * sizeof(float)), 0);
  dacpo_ply_cloud_free(&c);
  dacpo_ply_cloud_free(&c); // idempotent

  // Positions only.
  ASSERT_EQ(
      dacpo_ply_write(path.c_str(), sc.s.xyz, nullptr, 100, nullptr, err, sizeof(err)),
      DACPO_PLY_OK);
  ASSERT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK) << err;
  EXPECT_EQ(c.n, 100u);
  EXPECT_EQ(c.normals, nullptr);
  EXPECT_EQ(std::memcmp(c.xyz, sc.s.xyz, 300 * sizeof(float)), 0);
  dacpo_ply_cloud_free(&c);

  // Empty cloud.
  ASSERT_EQ(
      dacpo_ply_write(path.c_str(), nullptr, nullptr, 0, nullptr, err, sizeof(err)),
      DACPO_PLY_OK);
  ASSERT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK) << err;
  EXPECT_EQ(c.n, 0u);
  dacpo_ply_cloud_free(&c);
  std::remove(path.c_str());
}

// Georeferenced double coordinates: written as double, read back exactly by
// dacpo_ply_read_exact (xyz_exact bit for bit, xyz the offsets from vertex 0);
// dacpo_ply_read keeps its float contract (no xyz_exact, no origin).
TEST(DacpoPly, DoubleCoordinatesRoundTripExactly)
{
  const double xyz[9] = {4.0e5 + 0.123456789, 5.4e6 + 0.5, 120.25,
                         4.0e5 + 1.000000001, 5.4e6 + 0.75, 120.0,
                         4.0e5, 5.4e6, 119.0};
  const float nrm[9] = {0, 0, 1, 0, 1, 0, 1, 0, 0};
  const std::string path = TempPath("double.ply");
  char err[256];
  ASSERT_EQ(dacpo_ply_write_exact(path.c_str(), xyz, nrm, 3, nullptr, err, sizeof(err)),
            DACPO_PLY_OK)
      << err;
  dacpo_ply_cloud c;
  ASSERT_EQ(dacpo_ply_read_exact(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK) << err;
  ASSERT_NE(c.xyz_exact, nullptr);
  EXPECT_EQ(std::memcmp(c.xyz_exact, xyz, sizeof(xyz)), 0);
  for (int k = 0; k < 9; ++k) {
    EXPECT_EQ(c.xyz[k], static_cast<float>(xyz[k] - xyz[k % 3])) << k;
    EXPECT_EQ(c.normals[k], nrm[k]);
  }
  EXPECT_EQ(c.origin[0], xyz[0]);
  dacpo_ply_cloud_free(&c);
  ASSERT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK) << err;
  EXPECT_EQ(c.xyz_exact, nullptr);
  EXPECT_EQ(c.origin[0], 0.0);
  EXPECT_EQ(c.xyz[0], static_cast<float>(xyz[0]));
  dacpo_ply_cloud_free(&c);
  std::remove(path.c_str());
}

TEST(DacpoPly, ReadsExtraPropertiesElementsAndFormats)
{
  char err[256];
  dacpo_ply_cloud c;
  const std::string path = TempPath("extra.ply");

  // ASCII, CRLF lines, colour bytes and a face element after the vertices.
  const std::string ascii =
      "ply\r\nformat ascii 1.0\r\ncomment hi\r\nelement vertex 2\r\n"
      "property float x\r\nproperty uchar red\r\nproperty float y\r\nproperty float "
      "z\r\n"
      "property float nx\r\nproperty float ny\r\nproperty float nz\r\n"
      "element face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
      "1.5 255 2 3 0 0 1\r\n-1 0 -2 -3.25 1 0 0\r\n3 0 1 1\r\n";
  WriteBytes(path, ascii.data(), ascii.size());
  ASSERT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK) << err;
  ASSERT_EQ(c.n, 2u);
  ASSERT_NE(c.normals, nullptr);
  EXPECT_FLOAT_EQ(c.xyz[0], 1.5f);
  EXPECT_FLOAT_EQ(c.xyz[1], 2.0f);
  EXPECT_FLOAT_EQ(c.xyz[5], -3.25f);
  EXPECT_FLOAT_EQ(c.normals[2], 1.0f);
  EXPECT_FLOAT_EQ(c.normals[3], 1.0f);
  dacpo_ply_cloud_free(&c);

  // Binary little-endian: a face element with lists BEFORE the vertices, double
  // coordinates, uchar and short extras, a list inside the vertex, no normals.
  std::vector<unsigned char> bin;
  const std::string hdr =
      "ply\nformat binary_little_endian 1.0\nelement face 2\n"
      "property list uchar int vertex_indices\nproperty uchar flags\n"
      "element vertex 2\nproperty double x\nproperty uchar alpha\nproperty double y\n"
      "property short s\nproperty double z\nproperty list uchar float extra\n"
      "end_header\n";
  bin.insert(bin.end(), hdr.begin(), hdr.end());
  auto put = [&bin](const void* p, size_t len) {
    const unsigned char* b = static_cast<const unsigned char*>(p);
    bin.insert(bin.end(), b, b + len); // the test host is little-endian
  };
  const unsigned char three = 3, one = 1, zero = 0;
  const int32_t idx[3] = {0, 1, 0};
  put(&three, 1), put(idx, 12), put(&one, 1);
  put(&one, 1), put(idx, 4), put(&zero, 1);
  const double v0[3] = {0.25, -1.0, 7.0}, v1[3] = {1e3, 2.5, -0.125};
  const int16_t sh = -7;
  const float extra[2] = {9.0f, 8.0f};
  const unsigned char two = 2;
  put(&v0[0], 8), put(&one, 1), put(&v0[1], 8), put(&sh, 2), put(&v0[2], 8),
      put(&two, 1), put(extra, 8);
  put(&v1[0], 8), put(&one, 1), put(&v1[1], 8), put(&sh, 2), put(&v1[2], 8),
      put(&zero, 1);
  WriteBytes(path, bin.data(), bin.size());
  ASSERT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK) << err;
  ASSERT_EQ(c.n, 2u);
  EXPECT_EQ(c.normals, nullptr);
  const float want[6] = {0.25f, -1.0f, 7.0f, 1e3f, 2.5f, -0.125f};
  for (int k = 0; k < 6; ++k)
    EXPECT_FLOAT_EQ(c.xyz[k], want[k]);
  dacpo_ply_cloud_free(&c);

  // Binary big-endian floats.
  std::vector<unsigned char> be;
  const std::string bhdr = "ply\nformat binary_big_endian 1.0\nelement vertex 1\n"
                           "property float x\nproperty float y\nproperty float z\n"
                           "end_header\n";
  be.insert(be.end(), bhdr.begin(), bhdr.end());
  for (float f : {1.0f, -2.0f, 0.5f}) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    for (int s = 24; s >= 0; s -= 8)
      be.push_back(static_cast<unsigned char>(u >> s));
  }
  WriteBytes(path, be.data(), be.size());
  ASSERT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK) << err;
  ASSERT_EQ(c.n, 1u);
  EXPECT_FLOAT_EQ(c.xyz[0], 1.0f);
  EXPECT_FLOAT_EQ(c.xyz[1], -2.0f);
  EXPECT_FLOAT_EQ(c.xyz[2], 0.5f);
  dacpo_ply_cloud_free(&c);
  std::remove(path.c_str());
}

namespace {

// The valid PLY file good cut at several places (header and data) is rejected.
void
ExpectTruncatedFilesRejected(const std::string& path,
                             const std::vector<unsigned char>& good,
                             char (&err)[256],
                             dacpo_ply_cloud& c)
{
  for (size_t cut : {size_t(0),
                     size_t(2),
                     size_t(40),
                     size_t(150),
                     good.size() - 24 * 500,
                     good.size() - 24 * 250 - 7,
                     good.size() - 1}) {
    WriteBytes(path, good.data(), cut);
    EXPECT_NE(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK)
        << "cut at " << cut;
    EXPECT_GT(std::strlen(err), 0u);
    EXPECT_EQ(c.n, 0u);
    EXPECT_EQ(c.xyz, nullptr);
  }
  WriteBytes(path, good.data(), good.size() - 1);
  EXPECT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_ERR_FORMAT);
  EXPECT_NE(std::string(err).find("truncated"), std::string::npos) << err;
}

// Garbage bytes (fixed seed), and garbage after a valid first line, are rejected.
void
ExpectGarbageRejected(const std::string& path, char (&err)[256], dacpo_ply_cloud& c)
{
  std::vector<unsigned char> junk(5000);
  uint64_t x = 12345;
  for (auto& b : junk) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    b = static_cast<unsigned char>(x >> 56);
  }
  WriteBytes(path, junk.data(), junk.size());
  EXPECT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_ERR_FORMAT);
  std::vector<unsigned char> junk2(junk);
  std::memcpy(junk2.data(), "ply\n", 4);
  WriteBytes(path, junk2.data(), junk2.size());
  EXPECT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_ERR_FORMAT);
}

// Headers that lie or are malformed, and a huge header line, are rejected.
void
ExpectBadHeadersRejected(const std::string& path, char (&err)[256], dacpo_ply_cloud& c)
{
  const char* bad_headers[] = {
      // absurd count: rejected before allocating
      "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n",
      "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n\x01\x02",
      "ply\nformat binary_little_endian 1.0\nelement vertex -3\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n",
      "ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n",
      "ply\nelement vertex 0\nproperty float x\nend_header\n", // no format
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "end_header\n1 2\n", // no z
      "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int v\nend_header\n"
      "0\n", // no vertex
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n", // bad
                                                                                // type
      "ply\nformat ascii 1.0\nproperty float x\nend_header\n", // property first
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n1 2 abc\n",                     // bad ascii value
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", // no end_header
      "ply\nformat ascii 1.0\nbogus line\nend_header\n",
      // an ASCII row is one line: one value too many or too few shifts every
      // later point unless the line end is checked
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n1 0 0 7\n0 1 0\n",
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0\n1 0 0\n0 1 0\n",
  };
  for (const char* h : bad_headers) {
    WriteBytes(path, h, std::strlen(h));
    err[0] = '\0';
    EXPECT_NE(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_OK) << h;
    EXPECT_GT(std::strlen(err), 0u) << h;
    EXPECT_EQ(c.xyz, nullptr);
  }
  // A huge header line.
  std::string longline = "ply\ncomment " + std::string(5000, 'a') + "\n";
  WriteBytes(path, longline.data(), longline.size());
  EXPECT_EQ(dacpo_ply_read(path.c_str(), &c, err, sizeof(err)), DACPO_PLY_ERR_FORMAT);
}

} // namespace

TEST(DacpoPly, BadFilesGiveErrorsNotCrashes)
{
  char err[256];
  dacpo_ply_cloud c;
  const std::string path = TempPath("bad.ply");

  // Missing file.
  EXPECT_EQ(dacpo_ply_read((path + ".missing").c_str(), &c, err, sizeof(err)),
            DACPO_PLY_ERR_IO);
  EXPECT_GT(std::strlen(err), 0u);
  EXPECT_EQ(dacpo_ply_read(nullptr, &c, err, sizeof(err)), DACPO_PLY_ERR_ARGUMENT);
  EXPECT_EQ(dacpo_ply_read(path.c_str(), nullptr, err, sizeof(err)),
            DACPO_PLY_ERR_ARGUMENT);

  // Truncated: a valid file cut at several places (header and data).
  Scene sc(DACPO_SCENE_PLANE, 500, 1);
  ASSERT_EQ(
      dacpo_ply_write(
          path.c_str(), sc.s.xyz, sc.s.normals, sc.s.n, nullptr, err, sizeof(err)),
      DACPO_PLY_OK);
  const std::vector<unsigned char> good = ReadBytes(path);
  ExpectTruncatedFilesRejected(path, good, err, c);

  // Garbage bytes (fixed seed), and garbage after a valid first line.
  ExpectGarbageRejected(path, err, c);

  // Headers that lie or are malformed.
  ExpectBadHeadersRejected(path, err, c);

  // Writing to a directory that does not exist.
  EXPECT_EQ(dacpo_ply_write("/nonexistent_dir_dacpo/x.ply",
                            sc.s.xyz,
                            nullptr,
                            1,
                            nullptr,
                            err,
                            sizeof(err)),
            DACPO_PLY_ERR_IO);
  EXPECT_NE(std::string(err).find("cannot open"), std::string::npos) << err;
  EXPECT_EQ(
      dacpo_ply_write(path.c_str(), nullptr, nullptr, 5, nullptr, err, sizeof(err)),
      DACPO_PLY_ERR_ARGUMENT);
  std::remove(path.c_str());
}

// Fused views: view 0 stays where it is, every other view is moved rigidly by
// about fused_shift (plus the rotation's share), normals turn with it (unit
// length kept); bad values are refused.
TEST(DacpoScene, FusedViewsMoveCopiesRigidly)
{
  dacpo_scene_params sp;
  dacpo_scene_params_init(&sp);
  sp.target_points = 20000;
  dacpo_scene plain{}, fused{};
  char err[256] = "";
  ASSERT_EQ(dacpo_scene_generate(&sp, &plain, err, sizeof(err)), 0) << err;
  sp.fused_views = 3;
  sp.fused_shift = 0.01;
  sp.fused_angle = 0.2;
  ASSERT_EQ(dacpo_scene_generate(&sp, &fused, err, sizeof(err)), 0) << err;
  ASSERT_EQ(plain.n, fused.n);
  size_t same = 0, moved = 0;
  for (size_t i = 0; i < plain.n; ++i) {
    double d2 = 0.0, len2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double d = (double)fused.xyz[3 * i + k] - (double)plain.xyz[3 * i + k];
      d2 += d * d;
      len2 += (double)fused.normals[3 * i + k] * (double)fused.normals[3 * i + k];
    }
    EXPECT_NEAR(len2, 1.0, 1e-5);
    same += d2 < 1e-12;
    // a 0.2 degree turn moves a point of a 6 m room by at most ~1.4 cm
    moved += d2 > 1e-8 && d2 < 0.03 * 0.03;
  }
  // one view in three stays in place, the others move by millimetres
  EXPECT_GT(same, plain.n / 4);
  EXPECT_LT(same, plain.n / 2);
  EXPECT_EQ(same + moved, plain.n);
  dacpo_scene_free(&plain);
  dacpo_scene_free(&fused);

  dacpo_scene bad{};
  sp.fused_views = DACPO_SCENE_MAX_FUSED_VIEWS + 1;
  EXPECT_EQ(dacpo_scene_generate(&sp, &bad, err, sizeof(err)), -1);
  sp.fused_views = 3;
  sp.fused_shift = -1.0;
  EXPECT_EQ(dacpo_scene_generate(&sp, &bad, err, sizeof(err)), -1);
  sp.fused_shift = 0.01;
  sp.fused_angle = NAN;
  EXPECT_EQ(dacpo_scene_generate(&sp, &bad, err, sizeof(err)), -1);
}
