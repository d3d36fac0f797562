// SPDX-License-Identifier: BSD-3-Clause
// The scene mesh (dacpo_scene_mesh.c) with known answers: a closed sphere cut
// into 8 blocks must come back watertight (no edge used by one triangle only,
// so no crack along a block seam) and wound outward; an open square cut into
// 8 blocks may be open only along its own rim; the mesh does not depend on the
// thread count; bad input is refused.
#include <dacpo/dacpo.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

extern "C" {
#include "dacpo_scene_mesh.h"
}
#include "scene_fixture.hpp"

namespace {

using Scene = GeneratedScene;

struct Mesh {
  std::vector<float> v;
  std::vector<int32_t> t;
  std::vector<float> normals; // the points' output normals
  size_t
  faces() const
  {
    return t.size() / 3;
  }
};

// Orients the scene's ground-truth axes with keep_mesh = 1 and returns the mesh.
Mesh
orientWithMesh(const dacpo_scene& s, size_t blocks, unsigned threads)
{
  Mesh m;
  dacpo_ctx* ctx = nullptr;
  EXPECT_EQ(dacpo_ctx_create(&ctx), DACPO_OK);
  dacpo_params p;
  dacpo_params_init(&p);
  p.keep_mesh = 1;
  p.num_blocks = blocks;
  p.num_threads = threads;
  m.normals.assign(s.normals, s.normals + 3 * s.n);
  const dacpo_status st =
      dacpo_orient(ctx, &p, nullptr, nullptr, s.xyz, m.normals.data(), s.n);
  EXPECT_EQ(st, DACPO_OK) << dacpo_ctx_last_error(ctx);
  EXPECT_EQ(dacpo_ctx_stats(ctx)->num_blocks, blocks);
  EXPECT_GE(dacpo_ctx_stats(ctx)->stage_seconds[DACPO_STAGE_MESH], 0.0);
  const float* v = nullptr;
  const int32_t* t = nullptr;
  size_t nv = 0;
  const size_t nt = dacpo_ctx_mesh(ctx, &v, &nv, &t);
  if (nt) {
    m.v.assign(v, v + 3 * nv);
    m.t.assign(t, t + 3 * nt);
  }
  dacpo_ctx_free(ctx);
  return m;
}

// Midpoints of the edges used by exactly one triangle.
std::vector<std::array<double, 3>>
boundaryMidpoints(const Mesh& m)
{
  std::map<std::pair<int32_t, int32_t>, int> uses;
  for (size_t f = 0; f < m.faces(); ++f)
    for (int e = 0; e < 3; ++e) {
      int32_t a = m.t[3 * f + e], b = m.t[3 * f + (e + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<std::array<double, 3>> mids;
  for (const auto& [edge, count] : uses)
    if (count == 1) {
      std::array<double, 3> mid;
      for (int d = 0; d < 3; ++d)
        mid[d] = 0.5 * (m.v[3 * edge.first + d] + m.v[3 * edge.second + d]);
      mids.push_back(mid);
    }
  return mids;
}

// Face normal (unnormalised) and centroid of face f.
void
face(const Mesh& m, size_t f, double n[3], double c[3])
{
  const float* a = &m.v[3 * m.t[3 * f]];
  const float* b = &m.v[3 * m.t[3 * f + 1]];
  const float* d = &m.v[3 * m.t[3 * f + 2]];
  const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double e2[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  for (int k = 0; k < 3; ++k)
    c[k] = (a[k] + b[k] + d[k]) / 3.0;
}

TEST(SceneMesh, ClosedSphereInEightBlocksIsWatertightAndFacesOut)
{
  Scene sc(DACPO_SCENE_SPHERE, 20000, 1);
  ASSERT_TRUE(sc.ok);
  const Mesh m = orientWithMesh(sc.s, 8, 2);
  ASSERT_GT(m.faces(), 5000u);
  // every edge has two faces: no seam between the 8 blocks is left open
  EXPECT_EQ(boundaryMidpoints(m).size(), 0u);
  size_t out = 0, far = 0;
  for (size_t f = 0; f < m.faces(); ++f) {
    double n[3], c[3];
    face(m, f, n, c);
    out += n[0] * c[0] + n[1] * c[1] + n[2] * c[2] > 0.0;
    far += std::fabs(std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) - 1.0) > 0.02;
  }
  // the global sign of a closed object is outward, and the mesh follows it
  EXPECT_GE(out, m.faces() * 999 / 1000) << out << " of " << m.faces();
  EXPECT_EQ(far, 0u) << "faces off the unit sphere by more than 2 cm";
}

TEST(SceneMesh, OpenSquareInEightBlocksIsOpenOnlyAtItsRim)
{
  Scene sc(DACPO_SCENE_PLANE, 20000, 1);
  ASSERT_TRUE(sc.ok);
  const Mesh m = orientWithMesh(sc.s, 8, 2);
  ASSERT_GT(m.faces(), 10000u);
  const auto mids = boundaryMidpoints(m);
  ASSERT_GT(mids.size(), 100u) << "the square's rim is open";
  // spacing 2 m / sqrt(20000) = 1.4 cm: the rim lies within a few spacings of
  // |x| = 1 or |y| = 1; a seam between blocks would leave open edges inside
  size_t inside = 0;
  for (const auto& p : mids)
    inside += std::max(std::fabs(p[0]), std::fabs(p[1])) < 0.95;
  EXPECT_EQ(inside, 0u) << "open edges away from the rim (block seams)";
  // faces follow the output normals (all +z or all -z)
  const double out_z = m.normals[2] > 0.0f ? 1.0 : -1.0;
  size_t agree = 0;
  for (size_t f = 0; f < m.faces(); ++f) {
    double n[3], c[3];
    face(m, f, n, c);
    agree += n[2] * out_z > 0.0;
  }
  EXPECT_EQ(agree, m.faces());
}

TEST(SceneMesh, SameMeshForOneAndTwoThreads)
{
  Scene sc(DACPO_SCENE_ROOM, 20000, 3);
  ASSERT_TRUE(sc.ok);
  const Mesh one = orientWithMesh(sc.s, 8, 1);
  const Mesh two = orientWithMesh(sc.s, 8, 2);
  ASSERT_GT(one.faces(), 1000u);
  EXPECT_EQ(one.v, two.v);
  EXPECT_EQ(one.t, two.t);
}

TEST(SceneMesh, RefusesMissingInput)
{
  dacpo_mesh mesh{};
  dacpo_err err{};
  EXPECT_EQ(dacpo_scene_mesh(nullptr, &mesh, &err), DACPO_ERR_INVALID_ARGUMENT);
  dacpo_scene_mesh_input in{};
  EXPECT_EQ(dacpo_scene_mesh(&in, &mesh, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(err.msg).find("scene mesh"), std::string::npos) << err.msg;
  EXPECT_EQ(mesh.num_triangles, 0u);
}

} // namespace
