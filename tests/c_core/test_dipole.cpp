// SPDX-License-Identifier: BSD-3-Clause
// Stage 2: dipole-field energy (paper Eq. 1-2) and randomized greedy
// orientation of one block (Eq. 4), scored on synthetic shapes with known
// normals that were randomly flipped.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

extern "C" {
#include "dacpo_dipole.h"
}

namespace {

const double kPi = 3.14159265358979323846;

// A block with ground-truth normals; the normals handed to the stage are the
// ground truth times a random sign per point.
struct Shape {
  std::vector<double> xyz, truth, nrm;
  std::vector<int> flip;
  size_t
  size() const
  {
    return xyz.size() / 3;
  }
  void
  add(double x, double y, double z, double nx, double ny, double nz)
  {
    const double l = std::sqrt(nx * nx + ny * ny + nz * nz);
    xyz.insert(xyz.end(), {x, y, z});
    truth.insert(truth.end(), {nx / l, ny / l, nz / l});
  }
  void
  scramble(uint64_t seed)
  {
    dacpo_rng rng;
    dacpo_rng_seed(&rng, seed, 99);
    nrm = truth;
    flip.assign(size(), 1);
    for (size_t i = 0; i < size(); ++i)
      if (dacpo_rng_uniform(&rng) < 0.5) {
        flip[i] = -1;
        for (int d = 0; d < 3; ++d)
          nrm[3 * i + d] = -nrm[3 * i + d];
      }
  }
};

double
jitter(dacpo_rng* rng, double amp)
{
  return amp * (2.0 * dacpo_rng_uniform(rng) - 1.0);
}

dacpo_dipole_params
default_params()
{
  dacpo_dipole_params p = {};
  p.c = 4.0;
  p.orders = 5;
  p.neighbors = 32;
  p.graph_k = 10;
  p.final_sweep = 1;
  p.seed = 1;
  p.stream = 7;
  return p;
}

// The pipeline's stage-2 settings (dacpo_params_init) with the layer rule off.
dacpo_dipole_params
pipeline_params()
{
  dacpo_dipole_params p = default_params();
  p.c = 1.5;
  p.restarts = 16;
  p.final_sweep = 10;
  p.two_sheet = 3.0;
  return p;
}

// Share of points whose oriented normal matches the ground truth, up to one
// global sign.
double
score(const Shape& s, const std::vector<int8_t>& sign)
{
  size_t agree = 0;
  for (size_t i = 0; i < s.size(); ++i)
    agree += sign[i] * s.flip[i] > 0;
  const size_t best = agree > s.size() - agree ? agree : s.size() - agree;
  return (double)best / (double)s.size();
}

double
orient_score(const Shape& s, const dacpo_dipole_params& p)
{
  std::vector<int8_t> sign(s.size(), 0);
  dacpo_err err{};
  EXPECT_EQ(
      dacpo_dipole_orient(s.xyz.data(), s.nrm.data(), s.size(), &p, sign.data(), &err),
      DACPO_OK)
      << err.msg;
  for (int8_t v : sign)
    EXPECT_TRUE(v == 1 || v == -1);
  return score(s, sign);
}

Shape
plane_patch(size_t side, double h, uint64_t seed)
{
  Shape s;
  dacpo_rng rng;
  dacpo_rng_seed(&rng, seed, 1);
  for (size_t i = 0; i < side; ++i)
    for (size_t j = 0; j < side; ++j)
      s.add(i * h + jitter(&rng, 0.2 * h),
            j * h + jitter(&rng, 0.2 * h),
            jitter(&rng, 0.02 * h),
            jitter(&rng, 0.02),
            jitter(&rng, 0.02),
            1.0);
  s.scramble(seed);
  return s;
}

Shape
sphere(size_t n, uint64_t seed)
{
  Shape s;
  dacpo_rng rng;
  dacpo_rng_seed(&rng, seed, 2);
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(1.0 - z * z);
    const double x = r * std::cos(golden * i), y = r * std::sin(golden * i);
    const double rad = 1.0 + jitter(&rng, 0.005);
    s.add(rad * x, rad * y, rad * z, x, y, z);
  }
  s.scramble(seed);
  return s;
}

// Two parallel side x side sheets, spacing h, thickness h (the sheets are as
// close as neighbours within a sheet): the outward normals of the two sides
// are opposite.
// Two side x side sheets at spacing h facing away from each other: h apart
// with their grids over each other, or (gap > 0) gap apart with the lower grid
// shifted by half a spacing, so no point has a partner straight beneath it.
Shape
thin_board(size_t side, double h, uint64_t seed, double gap = 0.0)
{
  Shape s;
  dacpo_rng rng;
  dacpo_rng_seed(&rng, seed, 3);
  const double shift = gap > 0.0 ? 0.5 * h : 0.0;
  if (gap <= 0.0)
    gap = h;
  for (int sheet = 0; sheet < 2; ++sheet) {
    const double nz = sheet == 0 ? 1.0 : -1.0;
    const double off = sheet == 0 ? 0.0 : shift;
    for (size_t i = 0; i < side; ++i)
      for (size_t j = 0; j < side; ++j)
        s.add(i * h + off + jitter(&rng, 0.1 * h),
              j * h + off + jitter(&rng, 0.1 * h),
              nz * 0.5 * gap + jitter(&rng, 0.02 * h),
              0.0,
              0.0,
              nz);
  }
  s.scramble(seed);
  return s;
}

// A bookcase seen from the front: a back panel (z = 0, normal +z) with
// `boards` vertical dividers 0.5 h thick standing on it (faces at x_k -+ h/4,
// normals -x / +x, depth 8 h), at spacing h.
Shape
shelves_on_panel(size_t boards, double h, uint64_t seed)
{
  Shape s;
  dacpo_rng rng;
  dacpo_rng_seed(&rng, seed, 5);
  const double t = 0.5 * h, pitch = 12.0 * h;
  const size_t across = (size_t)((double)(boards + 1) * pitch / h), tall = 30;
  for (size_t i = 0; i < across; ++i)
    for (size_t j = 0; j < tall; ++j) {
      const double x = (i + 0.5) * h + jitter(&rng, 0.5 * h);
      bool under = false; // the boards cover the panel under them
      for (size_t k = 1; k <= boards; ++k)
        under = under || std::fabs(x - k * pitch) < 0.5 * t;
      if (!under)
        s.add(x, j * h + jitter(&rng, 0.5 * h), jitter(&rng, 0.02 * h), 0.0, 0.0, 1.0);
    }
  for (size_t k = 1; k <= boards; ++k)
    for (int f = -1; f <= 1; f += 2)
      for (size_t i = 0; i < 8; ++i)
        for (size_t j = 0; j < tall; ++j)
          s.add(k * pitch + f * 0.5 * t + jitter(&rng, 0.02 * h),
                j * h + jitter(&rng, 0.5 * h),
                (i + 1.0) * h + jitter(&rng, 0.5 * h),
                (double)f,
                0.0,
                0.0);
  s.scramble(seed);
  return s;
}

// Open half-cylinder, radius 1, outward normals.
Shape
half_cylinder(size_t around, size_t along, uint64_t seed)
{
  Shape s;
  dacpo_rng rng;
  dacpo_rng_seed(&rng, seed, 4);
  const double h = kPi / around;
  for (size_t a = 0; a < around; ++a)
    for (size_t l = 0; l < along; ++l) {
      const double t = (a + 0.5) * h + jitter(&rng, 0.1 * h);
      s.add(std::cos(t),
            std::sin(t),
            l * h + jitter(&rng, 0.1 * h),
            std::cos(t),
            std::sin(t),
            0.0);
    }
  s.scramble(seed);
  return s;
}

// Uniform position noise of +-amp per coordinate (normals stay exact axes).
Shape
with_position_noise(Shape s, double amp, uint64_t seed)
{
  dacpo_rng rng;
  dacpo_rng_seed(&rng, seed, 5);
  for (double& v : s.xyz)
    v += jitter(&rng, amp);
  return s;
}

} // namespace

TEST(DacpoDipole, EnergyPositiveSideBySide)
{
  // r perpendicular to both (parallel) normals: same orientation is favoured,
  // e = n.m / |r|^3 = 1 / 8 for |r| = 2.
  const double p[3] = {0, 0, 0}, q[3] = {2, 0, 0}, n[3] = {0, 0, 1};
  EXPECT_NEAR(dacpo_dipole_energy(p, n, q, n, 4.0), 1.0 / 8.0, 1e-15);
  EXPECT_GT(dacpo_dipole_energy(p, n, q, n, 2.0), 0.0);
}

TEST(DacpoDipole, EnergyNegativeStacked)
{
  // r parallel to the normals: e = -(c - 1) / |r|^3, negative for c > 1, so the
  // stacked point prefers the opposite normal (two sides of a thin sheet).
  const double p[3] = {1, 1, 1}, q[3] = {1, 1, 1.5}, n[3] = {0, 0, 1};
  const double m[3] = {0, 0, -1};
  EXPECT_NEAR(dacpo_dipole_energy(p, n, q, n, 4.0), -3.0 / 0.125, 1e-12);
  EXPECT_NEAR(dacpo_dipole_energy(p, n, q, n, 3.0), -2.0 / 0.125, 1e-12);
  EXPECT_NEAR(dacpo_dipole_energy(p, n, q, m, 4.0), 3.0 / 0.125, 1e-12);
}

TEST(DacpoDipole, EnergyGeneralDirectionMatchesFormula)
{
  // Hand evaluation of Eq. 1-2 at an oblique r.
  const double p[3] = {0, 0, 0}, q[3] = {1, 2, 2}; // |r| = 3
  const double n[3] = {1, 0, 0}, m[3] = {0, 0.6, 0.8};
  // r^.n = 1/3, r^.m = (1.2 + 1.6)/3, n.m = 0
  const double expect = -(2.0 * (1.0 / 3.0) * (2.8 / 3.0) - 0.0) / 27.0;
  EXPECT_NEAR(dacpo_dipole_energy(p, n, q, m, 2.0), expect, 1e-15);
  // Swapping the two points gives the same value (r -> -r twice).
  EXPECT_NEAR(dacpo_dipole_energy(q, m, p, n, 2.0), expect, 1e-15);
}

TEST(DacpoDipole, EnergyZeroForCoincidentPoints)
{
  const double p[3] = {1e3, 2e3, 3e3}, n[3] = {0, 0, 1};
  const double q[3] = {1e3, 2e3, 3e3 + 1e-11};
  EXPECT_EQ(dacpo_dipole_energy(p, n, p, n, 4.0), 0.0);
  EXPECT_EQ(dacpo_dipole_energy(p, n, q, n, 4.0), 0.0);
  const double o[3] = {0, 0, 0};
  EXPECT_EQ(dacpo_dipole_energy(o, n, o, n, 4.0), 0.0);
  // A small but genuine separation still counts.
  const double q2[3] = {1e3, 2e3, 3e3 + 1e-3};
  EXPECT_TRUE(std::isfinite(dacpo_dipole_energy(p, n, q2, n, 4.0)));
  EXPECT_LT(dacpo_dipole_energy(p, n, q2, n, 4.0), 0.0);
}

TEST(DacpoDipole, PlanePatchFullyConsistent)
{
  const Shape s = plane_patch(40, 0.01, 11);
  EXPECT_EQ(orient_score(s, default_params()), 1.0);
}

TEST(DacpoDipole, SphereConsistent)
{
  const Shape s = sphere(1500, 12);
  const double sc = orient_score(s, default_params());
  EXPECT_GE(sc, 0.99) << sc;
}

TEST(DacpoDipole, ThinBoardSidesOpposite)
{
  const Shape s = thin_board(30, 0.01, 13);
  const double sc = orient_score(s, default_params());
  EXPECT_GE(sc, 0.98) << sc;
}

TEST(DacpoDipole, HalfCylinderConsistent)
{
  const Shape s = half_cylinder(60, 40, 14);
  const double sc = orient_score(s, default_params());
  EXPECT_GE(sc, 0.99) << sc;
}

TEST(DacpoDipole, ThinBoardNeedsLargeC)
{
  // Paper §4.2: a larger c widens the region where a stacked point is pushed to
  // the opposite sign. Summed over the other sheet's points near one point (the
  // ones a K = 32 neighbourhood reaches), the field favours the true, opposite
  // normals at c = 4 but "same sign" at c = 1.5.
  const Shape s = thin_board(30, 0.01, 13);
  const size_t centre = 15 * 30 + 15; // top sheet
  const double* p = &s.xyz[3 * centre];
  const double* n = &s.truth[3 * centre];
  double sum4 = 0.0, sum15 = 0.0;
  for (size_t j = 900; j < 1800; ++j) { // bottom sheet
    const double* q = &s.xyz[3 * j];
    const double dx = q[0] - p[0], dy = q[1] - p[1];
    if (dx * dx + dy * dy > 2.5 * 2.5 * 1e-4)
      continue;
    sum4 += dacpo_dipole_energy(p, n, q, &s.truth[3 * j], 4.0);
    sum15 += dacpo_dipole_energy(p, n, q, &s.truth[3 * j], 1.5);
  }
  EXPECT_GT(sum4, 0.0);
  EXPECT_LT(sum15, 0.0);
  dacpo_dipole_params prm = default_params();
  prm.c = 4.0;
  EXPECT_GE(orient_score(s, prm), 0.98);
}

TEST(DacpoDipole, NoisyHalfCylinderPrefersSmallC)
{
  // Position noise of ~40 % of the spacing: c = 2 (the paper's noisy setting)
  // stays consistent.
  const Shape s = with_position_noise(half_cylinder(60, 40, 14), 0.02, 2);
  dacpo_dipole_params p = default_params();
  p.c = 2.0;
  const double sc = orient_score(s, p);
  EXPECT_GE(sc, 0.99) << sc;
}

// Layers of one surface as a coarse depth sensor records them: `count`
// copies of a side x side grid stacked `step` spacings apart along their common
// axis, each shifted sideways by `shift` columns, all facing the sensor (+z).
Shape
stacked_layers(
    size_t side, size_t count, double step, size_t shift, double h, uint64_t seed)
{
  Shape s;
  dacpo_rng rng;
  dacpo_rng_seed(&rng, seed, 3);
  for (size_t l = 0; l < count; ++l)
    for (size_t i = 0; i < side; ++i)
      for (size_t j = 0; j < side; ++j)
        s.add((double)(i + l * shift) * h + jitter(&rng, 0.1 * h),
              j * h + jitter(&rng, 0.1 * h),
              step * h * (double)l,
              jitter(&rng, 0.01),
              jitter(&rng, 0.01),
              1.0);
  s.scramble(seed);
  return s;
}

TEST(DacpoDipole, StackedLayersOfOneSurfaceFaceOneWay)
{
  // Three copies of a plane 2.5 spacings apart (beyond the two-sheet window of
  // 2 spacings; a real Kinect frame showed 3.5), shifted sideways, all facing
  // +z. Eq. 1's stacked term says "opposite" for c > 1: measured, the layers
  // come out alternating (2/3 right) without the layer rule. No point has a
  // second sheet, so the block counts as seen from one side and the rule makes
  // the layers one surface.
  dacpo_dipole_params p = pipeline_params();
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    const Shape s = stacked_layers(30, 3, 2.5, 10, 0.01, seed);
    p.seed = seed;
    p.layers = 0.0;
    EXPECT_LE(orient_score(s, p), 0.70) << seed;
    p.layers = 0.5;
    EXPECT_GE(orient_score(s, p), 0.999) << seed;
  }
}

TEST(DacpoDipole, LayerRuleLeavesThinPartsOpposite)
{
  // Two faces of a thin board one spacing apart are two sheets, not layers:
  // the block is two-sided, the rule stays off and the faces stay opposite.
  dacpo_dipole_params p = pipeline_params();
  p.layers = 0.5;
  EXPECT_GE(orient_score(thin_board(30, 0.01, 13), p), 0.98);
}

TEST(DacpoDipole, SideCueSeparatesFacesUnderOneSpacing)
{
  // Faces 0.4 spacing apart, grids shifted by half a spacing: without the cue
  // the pair rules leave the rims and patches inside wrong (measured 0.948-0.949
  // right, seeds 1-3); the side cue turns the faces apart and marks the points
  // as thin (thin_out), so that stage 3 keeps them.
  dacpo_dipole_params p = pipeline_params();
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    const Shape s = thin_board(40, 0.01, seed, 0.004);
    p.seed = seed;
    p.sides = 0.0;
    EXPECT_LE(orient_score(s, p), 0.96) << seed;
    p.sides = 0.5;
    std::vector<uint8_t> thin(s.size(), 0);
    p.thin_out = thin.data();
    EXPECT_GE(orient_score(s, p), 0.99) << seed;
    size_t marked = 0;
    for (uint8_t t : thin)
      marked += t;
    EXPECT_GE(marked, s.size() * 9 / 10) << seed;
    p.thin_out = nullptr;
  }
  // a single plane: the cue stays silent, nothing is marked
  const Shape plane = plane_patch(50, 0.01, 4);
  p.sides = 0.5;
  std::vector<uint8_t> thin(plane.size(), 1);
  p.thin_out = thin.data();
  EXPECT_GE(orient_score(plane, p), 0.999);
  for (uint8_t t : thin)
    EXPECT_EQ(t, 0);
}

TEST(DacpoDipole, ShelvesOnAPanelFaceOutOfTheBoards)
{
  // Dividers 0.5 spacing thick standing on a back panel. Near the panel, Eq. 1
  // relates each face of a board to the panel on both sides of it, and the
  // panel beyond the other face says "turn over". The side cue marks the panel
  // behind the board as hidden from that face and drops those pairs. Measured
  // over seeds 1-6 (8 restarts): without the hidden pairs min 0.9715, mean
  // 0.9938; with them min 0.9882, mean 0.9974. (At 16 restarts the vote hides
  // the difference: 0.9877 / 0.9969 against 0.9882 / 0.9970.)
  dacpo_dipole_params p = pipeline_params();
  p.sides = 0.001;
  p.restarts = 8;
  double sum = 0.0;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const Shape s = shelves_on_panel(4, 0.01, seed);
    p.seed = seed;
    const double right = orient_score(s, p);
    EXPECT_GE(right, 0.985) << seed;
    sum += right;
  }
  EXPECT_GE(sum / 6.0, 0.995);
}

TEST(DacpoDipole, IslandsOfABlockTakeTheFieldOfThePlacedPoints)
{
  // Two coplanar patches 20 patch widths apart in one block (a component
  // joined by a bridge, or a part beyond every neighbourhood): no k-NN pair
  // joins them, and a BFS tree starting on the second patch used to take an
  // arbitrary sign, so the restarts voted on a coin. The Eq. 1 field of the
  // placed patch says "same way" (n.m / r^3 > 0 for r along the plane).
  const Shape a = plane_patch(20, 0.01, 5);
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    Shape s;
    for (int copy = 0; copy < 2; ++copy)
      for (size_t i = 0; i < a.size(); ++i)
        s.add(a.xyz[3 * i] + copy * 4.0,
              a.xyz[3 * i + 1],
              a.xyz[3 * i + 2],
              a.truth[3 * i],
              a.truth[3 * i + 1],
              a.truth[3 * i + 2]);
    s.scramble(seed);
    dacpo_dipole_params p = pipeline_params();
    p.seed = seed;
    EXPECT_EQ(orient_score(s, p), 1.0) << seed;
  }
}

TEST(DacpoDipole, VotingOverOrdersBeatsOneOrder)
{
  // With c = 4 on the noisy half-cylinder single greedy orders flip patches; the
  // aligned majority vote of M = 5 orders repairs most of them (measured: mean
  // 0.86 for M = 1 against 0.97 for M = 5 over seeds 1-6).
  const Shape s = with_position_noise(half_cylinder(60, 40, 14), 0.02, 2);
  double one = 0.0, five = 0.0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    dacpo_dipole_params p = default_params();
    p.seed = seed;
    p.stream = 3;
    p.orders = 1;
    one += orient_score(s, p) / 3.0;
    p.orders = 5;
    five += orient_score(s, p) / 3.0;
  }
  EXPECT_GT(five, one + 0.01) << "M=1 " << one << " M=5 " << five;
  EXPECT_GE(five, 0.95);
}

TEST(DacpoDipole, DeterministicForSeedAndStream)
{
  const Shape s = sphere(800, 15);
  dacpo_dipole_params p = default_params();
  p.final_sweep = 0;
  std::vector<int8_t> a(s.size()), b(s.size());
  dacpo_err err{};
  ASSERT_EQ(
      dacpo_dipole_orient(s.xyz.data(), s.nrm.data(), s.size(), &p, a.data(), &err),
      DACPO_OK);
  ASSERT_EQ(
      dacpo_dipole_orient(s.xyz.data(), s.nrm.data(), s.size(), &p, b.data(), &err),
      DACPO_OK);
  EXPECT_EQ(a, b);
}

TEST(DacpoDipole, SingleOrderWithoutSweepStillOrientsPlane)
{
  // One order (no vote, no sweep) is plain greedy propagation: a clean plane
  // must already come out consistent.
  const Shape s = plane_patch(20, 1.0, 16);
  dacpo_dipole_params p = default_params();
  p.orders = 1;
  p.final_sweep = 0;
  EXPECT_EQ(orient_score(s, p), 1.0);
}

TEST(DacpoDipole, TinyAndEmptyInputs)
{
  dacpo_dipole_params p = default_params();
  dacpo_err err{};
  EXPECT_EQ(dacpo_dipole_orient(nullptr, nullptr, 0, &p, nullptr, &err), DACPO_OK);

  const double one_xyz[3] = {1, 2, 3}, one_n[3] = {0, 0, -1};
  int8_t one = 0;
  EXPECT_EQ(dacpo_dipole_orient(one_xyz, one_n, 1, &p, &one, &err), DACPO_OK);
  EXPECT_EQ(one, 1);

  // Two side-by-side points with opposite axes: the second must be flipped
  // relative to the first (K is clamped to n - 1 = 1).
  const double two_xyz[6] = {0, 0, 0, 1, 0, 0}, two_n[6] = {0, 0, 1, 0, 0, -1};
  int8_t two[2] = {0, 0};
  EXPECT_EQ(dacpo_dipole_orient(two_xyz, two_n, 2, &p, two, &err), DACPO_OK);
  EXPECT_EQ(two[0] * two[1], -1);
}

TEST(DacpoDipole, RejectsBadArguments)
{
  dacpo_dipole_params p = default_params();
  const double xyz[6] = {0, 0, 0, 1, 0, 0}, n[6] = {0, 0, 1, 0, 0, 1};
  int8_t s[2];
  dacpo_err err{};
  EXPECT_EQ(dacpo_dipole_orient(xyz, n, 2, nullptr, s, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_dipole_orient(nullptr, n, 2, &p, s, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_dipole_orient(xyz, n, 2, &p, nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  p.orders = 0;
  EXPECT_EQ(dacpo_dipole_orient(xyz, n, 2, &p, s, &err), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(err.msg).find("orders"), std::string::npos) << err.msg;
  p.orders = 17;
  EXPECT_EQ(dacpo_dipole_orient(xyz, n, 2, &p, s, &err), DACPO_ERR_INVALID_ARGUMENT);
  p = default_params();
  p.neighbors = 0;
  EXPECT_EQ(dacpo_dipole_orient(xyz, n, 2, &p, s, &err), DACPO_ERR_INVALID_ARGUMENT);
}

TEST(DacpoDipole, TimingReport)
{
  // Not a benchmark: records the cost of one block at the default sizes.
  for (size_t side : {50u, 100u}) {
    const Shape s = plane_patch(side, 0.01, 17);
    std::vector<int8_t> sign(s.size());
    dacpo_dipole_params p = default_params();
    dacpo_err err{};
    const double t0 = dacpo_now();
    ASSERT_EQ(dacpo_dipole_orient(
                  s.xyz.data(), s.nrm.data(), s.size(), &p, sign.data(), &err),
              DACPO_OK);
    const double t = dacpo_now() - t0;
    std::printf("[ timing   ] dipole n=%zu K=32 M=5: %.2f ms\n", s.size(), 1e3 * t);
    EXPECT_LT(t, 2.0); // generous: catches accidental quadratic work only
    EXPECT_EQ(score(s, sign), 1.0);
  }
}
TEST(DacpoDipole, RestartVoteHoldsOnEverySeed)
{
  // Shelves on a panel without the side cue: the boards' relation to the panel
  // is weak, and which single restart gets it right is close to a coin toss.
  // The point-wise vote of 8 restarts holds on every run seed. Measured over
  // seeds 1-200 (two random streams of the orders): mean 0.878-0.880 right,
  // every window of 32 seeds 0.873-0.886 on average and at least 0.738;
  // keeping the restart with the highest block energy, an option until
  // 2026-12-04, gave 0.686-0.921 on seeds 1-8.
  const Shape s = shelves_on_panel(4, 0.01, 3);
  dacpo_dipole_params p = pipeline_params();
  p.restarts = 8;
  double lo = 1.0, sum = 0.0;
  const int seeds = 32;
  for (uint64_t seed = 1; seed <= (uint64_t)seeds; ++seed) {
    p.seed = seed;
    const double right = orient_score(s, p);
    lo = std::min(lo, right);
    sum += right;
  }
  EXPECT_GE(sum / seeds, 0.86);
  EXPECT_GE(lo, 0.70);
}

// The restarts run are reported: a clean sphere gives the same signs on every
// restart, so the block stops after the first four; the shelves' restarts
// disagree on some seed, and then all of them run; one restart is one.
TEST(DacpoDipole, ReportsTheRestartsItRan)
{
  std::vector<int8_t> sign;
  size_t ran = 0;
  dacpo_err err{};
  auto run = [&](const Shape& s, dacpo_dipole_params p) {
    sign.assign(s.size(), 0);
    ran = 0;
    p.restarts_out = &ran;
    EXPECT_EQ(
        dacpo_dipole_orient(s.xyz.data(), s.nrm.data(), s.size(), &p, sign.data(), &err),
        DACPO_OK)
        << err.msg;
  };
  const Shape ball = sphere(1500, 5);
  run(ball, pipeline_params());
  EXPECT_EQ(ran, 4u);
  EXPECT_EQ(score(ball, sign), 1.0);
  dacpo_dipole_params one = pipeline_params();
  one.restarts = 1;
  run(ball, one);
  EXPECT_EQ(ran, 1u);
  const Shape shelves = shelves_on_panel(4, 0.01, 3);
  size_t most = 0;
  dacpo_dipole_params p = pipeline_params();
  p.restarts = 8;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    p.seed = seed;
    run(shelves, p);
    EXPECT_TRUE(ran == 4 || ran == 8) << ran;
    most = std::max(most, ran);
  }
  EXPECT_EQ(most, 8u);
}
