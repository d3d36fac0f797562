// SPDX-License-Identifier: BSD-3-Clause
// After stage 5: large smooth surfaces keep one orientation
// (dacpo_surface_vote.c). Known answers on generated surfaces at spacing h:
// a patch turned over inside a plane or a cylinder is turned back; the two
// faces of a board half a spacing thick, and two perpendicular faces, are never
// one surface; a surface under the size threshold is left alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

extern "C" {
#include "dacpo_kdtree.h"
#include "dacpo_rng.h"
#include "dacpo_surface_vote.h"
}

namespace {

const double kH = 0.02; // sampling spacing
const size_t kK = 10;   // neighbours, as the pipeline's k-NN graph

struct Cloud {
  std::vector<double> xyz, axis, truth; // axis: unit, random sign (as PCA gives)
  dacpo_rng rng;
  Cloud() { dacpo_rng_seed(&rng, 11, 3); }
  void
  add(double x, double y, double z, double nx, double ny, double nz)
  {
    const double s = dacpo_rng_uniform(&rng) < 0.5 ? -1.0 : 1.0;
    xyz.insert(xyz.end(), {x, y, z});
    axis.insert(axis.end(), {s * nx, s * ny, s * nz});
    truth.insert(truth.end(), {nx, ny, nz});
  }
  size_t
  size() const
  {
    return xyz.size() / 3;
  }
  // Jittered grid of m x m points in the plane z = z0, normal (0, 0, nz).
  void
  plane(int m, double z0, double nz)
  {
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j)
        add((i + 0.3 + 0.4 * dacpo_rng_uniform(&rng)) * kH,
            (j + 0.3 + 0.4 * dacpo_rng_uniform(&rng)) * kH,
            z0,
            0.0,
            0.0,
            nz);
  }
};

// Symmetric k-NN adjacency in CSR form, as dacpo_adjacency_build gives it.
struct Adjacency {
  std::vector<size_t> start;
  std::vector<int32_t> nbr;
  dacpo_adjacency adj{};
  explicit Adjacency(const Cloud& c)
  {
    const size_t n = c.size();
    dacpo_err err{};
    dacpo_kdtree* tree = nullptr;
    EXPECT_EQ(dacpo_kdtree_build(c.xyz.data(), n, &tree, &err), DACPO_OK);
    std::vector<std::vector<int32_t>> rows(n);
    std::vector<int32_t> buf(kK + 1);
    std::vector<double> dist(kK + 1);
    for (size_t i = 0; i < n; ++i) {
      const size_t got = dacpo_kdtree_knn(tree, &c.xyz[3 * i], kK + 1, buf.data(), dist.data());
      for (size_t f = 0; f < got; ++f)
        if ((size_t)buf[f] != i) {
          rows[i].push_back(buf[f]);
          rows[(size_t)buf[f]].push_back((int32_t)i);
        }
    }
    dacpo_kdtree_free(tree);
    start.push_back(0);
    for (auto& r : rows) {
      std::sort(r.begin(), r.end());
      r.erase(std::unique(r.begin(), r.end()), r.end());
      nbr.insert(nbr.end(), r.begin(), r.end());
      start.push_back(nbr.size());
    }
    adj.n = n;
    adj.start = start.data();
    adj.nbr = nbr.data();
  }
};

// Signs that make every normal match the truth.
std::vector<int8_t>
rightSigns(const Cloud& c)
{
  std::vector<int8_t> s(c.size());
  for (size_t i = 0; i < c.size(); ++i) {
    const double* a = &c.axis[3 * i];
    const double* t = &c.truth[3 * i];
    s[i] = a[0] * t[0] + a[1] * t[1] + a[2] * t[2] > 0.0 ? 1 : -1;
  }
  return s;
}

size_t
wrongCount(const Cloud& c, const std::vector<int8_t>& s)
{
  const std::vector<int8_t> r = rightSigns(c);
  size_t w = 0;
  for (size_t i = 0; i < s.size(); ++i)
    w += s[i] != r[i];
  return w;
}

struct Vote {
  size_t turned = 0, patches = 0;
  dacpo_status status = DACPO_OK;
};

Vote
runVote(const Cloud& c, std::vector<int8_t>& s, size_t min_points)
{
  Adjacency a(c);
  dacpo_err err{};
  Vote v;
  v.status = dacpo_surface_vote(
      c.xyz.data(), c.axis.data(), &a.adj, 8.0, min_points, s.data(), &v.turned, &v.patches, &err);
  return v;
}

// The points of the plane cloud inside a square of side `side` spacings.
template <class F>
void
turnWhere(const Cloud& c, std::vector<int8_t>& s, F inside)
{
  for (size_t i = 0; i < c.size(); ++i)
    if (inside(&c.xyz[3 * i]))
      s[i] = (int8_t)-s[i];
}

TEST(SurfaceVote, TurnsBackAPatchTurnedOverInsideAPlane)
{
  Cloud c;
  c.plane(40, 0.0, 1.0); // 1,600 points
  std::vector<int8_t> s = rightSigns(c);
  turnWhere(c, s, [](const double* p) { return p[0] < 10 * kH && p[1] < 10 * kH; });
  const size_t before = wrongCount(c, s);
  EXPECT_EQ(before, 100u);
  const Vote v = runVote(c, s, 1000);
  ASSERT_EQ(v.status, DACPO_OK);
  EXPECT_EQ(v.patches, 1u);
  EXPECT_EQ(v.turned, 100u);
  EXPECT_EQ(wrongCount(c, s), 0u);
}

TEST(SurfaceVote, LeavesSurfacesUnderTheThresholdAlone)
{
  Cloud c;
  c.plane(40, 0.0, 1.0);
  std::vector<int8_t> s = rightSigns(c);
  turnWhere(c, s, [](const double* p) { return p[0] < 10 * kH && p[1] < 10 * kH; });
  const Vote v = runVote(c, s, 2000);
  ASSERT_EQ(v.status, DACPO_OK);
  EXPECT_EQ(v.patches, 0u);
  EXPECT_EQ(v.turned, 0u);
  EXPECT_EQ(wrongCount(c, s), 100u);
}

// A minority over a fifth of the surface is what two faces merged into one
// patch look like (about half each): the vote abstains. A quarter of a plane
// turned over stays as it is; 15 % is turned back.
TEST(SurfaceVote, AbstainsWhereTheMinorityIsOverAFifth)
{
  Cloud c;
  c.plane(40, 0.0, 1.0);
  std::vector<int8_t> s = rightSigns(c);
  turnWhere(c, s, [](const double* p) { return p[0] < 10 * kH; });
  EXPECT_EQ(wrongCount(c, s), 400u);
  Vote v = runVote(c, s, 1000);
  ASSERT_EQ(v.status, DACPO_OK);
  EXPECT_EQ(v.patches, 1u);
  EXPECT_EQ(v.turned, 0u);
  EXPECT_EQ(wrongCount(c, s), 400u);
  s = rightSigns(c);
  turnWhere(c, s, [](const double* p) { return p[0] < 6 * kH; });
  EXPECT_EQ(wrongCount(c, s), 240u);
  v = runVote(c, s, 1000);
  EXPECT_EQ(v.turned, 240u);
  EXPECT_EQ(wrongCount(c, s), 0u);
}

// A board half a spacing thick: the faces are each other's nearest
// neighbours with parallel axes but lie off each other's tangent plane, so
// they stay two surfaces facing away from each other; a square turned over on
// the top face is turned back there only.
TEST(SurfaceVote, KeepsTheTwoFacesOfAThinBoardApart)
{
  Cloud c;
  c.plane(40, 0.0, -1.0);
  c.plane(40, 0.5 * kH, 1.0);
  std::vector<int8_t> s = rightSigns(c);
  Vote v = runVote(c, s, 1000);
  ASSERT_EQ(v.status, DACPO_OK);
  EXPECT_EQ(v.patches, 2u);
  EXPECT_EQ(v.turned, 0u);
  turnWhere(c, s, [](const double* p) { return p[2] > 0.25 * kH && p[0] < 5 * kH; });
  EXPECT_EQ(wrongCount(c, s), 200u);
  v = runVote(c, s, 1000);
  EXPECT_EQ(v.turned, 200u);
  EXPECT_EQ(wrongCount(c, s), 0u);
}

// A floor and a wall meeting at a right angle: never one surface, so a wall
// turned over as a whole (what stage 5 decides for a block) stays as it is.
TEST(SurfaceVote, DoesNotRelatePerpendicularFaces)
{
  Cloud c;
  c.plane(40, 0.0, 1.0);
  for (int i = 0; i < 40; ++i)
    for (int j = 1; j <= 30; ++j)
      c.add((i + 0.5) * kH, 0.0, j * kH, 0.0, 1.0, 0.0);
  std::vector<int8_t> s = rightSigns(c);
  turnWhere(c, s, [](const double* p) { return p[2] > 0.5 * kH; });
  const Vote v = runVote(c, s, 1000);
  ASSERT_EQ(v.status, DACPO_OK);
  EXPECT_EQ(v.turned, 0u);
  EXPECT_EQ(wrongCount(c, s), 1200u);
}

// Around a cylinder (radius 15 spacings: 3.8 degrees between neighbours) the
// relation is carried along the curve; a strip turned over is turned back.
TEST(SurfaceVote, FollowsACurvedSurface)
{
  Cloud c;
  const double r = 15 * kH;
  const int around = (int)(2 * M_PI * r / kH), along = 25;
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < along; ++j) {
      const double t = 2 * M_PI * i / around;
      c.add(r * std::cos(t), r * std::sin(t), j * kH, std::cos(t), std::sin(t), 0.0);
    }
  ASSERT_GE(c.size(), 2000u);
  std::vector<int8_t> s = rightSigns(c);
  turnWhere(c, s, [](const double* p) { return p[0] > 0.0 && p[1] > 0.0 && p[1] < p[0]; });
  const size_t before = wrongCount(c, s);
  EXPECT_GT(before, 200u);
  const Vote v = runVote(c, s, 1000);
  ASSERT_EQ(v.status, DACPO_OK);
  EXPECT_EQ(v.turned, before);
  EXPECT_EQ(wrongCount(c, s), 0u);
}

TEST(SurfaceVote, RejectsBadArguments)
{
  Cloud c;
  c.plane(5, 0.0, 1.0);
  Adjacency a(c);
  std::vector<int8_t> s = rightSigns(c);
  dacpo_err err{};
  EXPECT_EQ(dacpo_surface_vote(nullptr, c.axis.data(), &a.adj, 8.0, 10, s.data(), nullptr, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_surface_vote(c.xyz.data(), c.axis.data(), &a.adj, 0.0, 10, s.data(), nullptr, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_surface_vote(c.xyz.data(), c.axis.data(), &a.adj, 90.0, 10, s.data(), nullptr, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_surface_vote(c.xyz.data(), c.axis.data(), &a.adj, 8.0, 10, nullptr, nullptr, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
}

} // namespace
