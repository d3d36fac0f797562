// SPDX-License-Identifier: BSD-3-Clause
// iPSR with Neumann boundary (stage 3, dacpo_ipsr.c): flipped normals on open
// sheets are repaired, thin boards keep opposite sides, wings are trimmed while
// interior gaps stay covered, and the block mesh covers the own points only.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

extern "C" {
#include "dacpo_ipsr.h"
#include "dacpo_kdtree.h"
}

namespace {

const double kPi = 3.14159265358979323846;

struct Cloud {
  std::vector<double> p, n, gt;
  size_t
  size() const
  {
    return p.size() / 3;
  }
  void
  add(double x, double y, double z, double nx, double ny, double nz)
  {
    double l = std::sqrt(nx * nx + ny * ny + nz * nz);
    p.insert(p.end(), {x, y, z});
    gt.insert(gt.end(), {nx / l, ny / l, nz / l});
  }
  // Initial normals: ground truth with a share flipped at random.
  void
  flip(double share, uint32_t seed)
  {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    n = gt;
    for (size_t i = 0; i < size(); ++i)
      if (U(rng) < share)
        for (int a = 0; a < 3; ++a)
          n[3 * i + a] = -n[3 * i + a];
  }
  // Percentage of normals more than 90 degrees from the truth, up to one
  // global sign (the paper's metric).
  double
  wrong_percent() const
  {
    size_t w = 0;
    for (size_t i = 0; i < size(); ++i)
      w += n[3 * i] * gt[3 * i] + n[3 * i + 1] * gt[3 * i + 1] +
               n[3 * i + 2] * gt[3 * i + 2] <
           0;
    double pct = 100.0 * (double)w / (double)size();
    return std::min(pct, 100.0 - pct);
  }
};

// z = 0.15 sin(3x) cos(2y) over [-1, 1]^2 (uniform in x, y).
Cloud
wavy_sheet(size_t count, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Cloud c;
  for (size_t i = 0; i < count; ++i) {
    double x = U(rng), y = U(rng);
    double dx = 0.45 * std::cos(3 * x) * std::cos(2 * y);
    double dy = -0.3 * std::sin(3 * x) * std::sin(2 * y);
    c.add(x, y, 0.15 * std::sin(3 * x) * std::cos(2 * y), -dx, -dy, 1.0);
  }
  return c;
}

Cloud
half_cylinder(size_t count, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Cloud c;
  for (size_t i = 0; i < count; ++i) {
    double t = kPi * U(rng), y = 2 * U(rng) - 1;
    c.add(std::cos(t), y, std::sin(t), std::cos(t), 0, std::sin(t));
  }
  return c;
}

// A board 40 x 30 x 2 cm sampled on all six faces at about 1 cm (jittered
// grid), normals out of the solid: top and bottom are 2 cm apart.
Cloud
thin_board(uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> J(-0.003, 0.003);
  const double sx = 0.40, sy = 0.30, t = 0.02, step = 0.01;
  Cloud c;
  for (double x = -sx / 2; x <= sx / 2 + 1e-9; x += step)
    for (double y = -sy / 2; y <= sy / 2 + 1e-9; y += step) {
      c.add(x + J(rng), y + J(rng), t / 2, 0, 0, 1);
      c.add(x + J(rng), y + J(rng), -t / 2, 0, 0, -1);
    }
  for (double z = -t / 2 + step / 2; z < t / 2; z += step) {
    for (double x = -sx / 2; x <= sx / 2 + 1e-9; x += step) {
      c.add(x + J(rng), sy / 2, z, 0, 1, 0);
      c.add(x + J(rng), -sy / 2, z, 0, -1, 0);
    }
    for (double y = -sy / 2 + step; y < sy / 2 - 1e-9; y += step) {
      c.add(sx / 2, y + J(rng), z, 1, 0, 0);
      c.add(-sx / 2, y + J(rng), z, -1, 0, 0);
    }
  }
  return c;
}

// Plane patch [-1, 1]^2 in z = 0 with a circular hole of radius `hole` at the
// centre and a small gap of radius `gap` at (0.6, 0.6), jittered grid of step
// `step`, normal +z.
Cloud
holed_plane(double step, double hole, double gap, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> J(-0.3 * step, 0.3 * step);
  Cloud c;
  for (double y = -1; y <= 1 + 1e-9; y += step)
    for (double x = -1; x <= 1 + 1e-9; x += step) {
      double px = x + J(rng), py = y + J(rng);
      if (px * px + py * py > hole * hole &&
          (px - 0.6) * (px - 0.6) + (py - 0.6) * (py - 0.6) > gap * gap)
        c.add(px, py, 0.0, 0, 0, 1);
    }
  return c;
}

struct IpsrRun {
  dacpo_ipsr_stats stats{};
  dacpo_mesh mesh{};
  ~IpsrRun() { dacpo_mesh_free(&mesh); }
};

void
run(Cloud* c, const dacpo_ipsr_params& prm, IpsrRun* r, size_t n_own = 0)
{
  dacpo_err err{};
  if (n_own == 0)
    n_own = c->size();
  ASSERT_EQ(
      dacpo_ipsr_block(
          c->p.data(), c->n.data(), c->size(), n_own, &prm, &r->mesh, &r->stats, &err),
      DACPO_OK)
      << err.msg;
}

void
centroid(const dacpo_mesh& m, size_t f, double c[3])
{
  for (int a = 0; a < 3; ++a)
    c[a] = (m.vertices[3 * m.triangles[3 * f] + a] +
            m.vertices[3 * m.triangles[3 * f + 1] + a] +
            m.vertices[3 * m.triangles[3 * f + 2] + a]) /
           3.0;
}

} // namespace

TEST(DacpoIpsr, WavySheetWithFlippedNormalsConverges)
{
  Cloud c = wavy_sheet(2500, 11);
  c.flip(0.3, 12);
  ASSERT_GT(c.wrong_percent(), 25.0);
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  IpsrRun r;
  run(&c, prm, &r);
  EXPECT_LT(c.wrong_percent(), 1.0);
  EXPECT_TRUE(r.stats.converged);
  EXPECT_LE(r.stats.iterations, 20u);
  EXPECT_GE(r.stats.faces_total, r.stats.faces);
  EXPECT_LE(r.stats.faces_total, r.stats.iterations * r.stats.faces * 2);
  EXPECT_LT(r.stats.surfaces_reused, r.stats.iterations);
  EXPECT_LE(r.stats.peak_bytes, (size_t)64 << 20);
  EXPECT_GE(r.stats.resolution, 32u);
  EXPECT_LE(r.stats.resolution, 128u);
}

// From settle_start on, an iteration that turns no sample over ends the block.
// A wavy sheet with true normals: no iteration turns a sample, yet the normals
// still move by more than the convergence bound (the rim follows the new
// surface), so the sign test alone ends the run: after iteration settle_start
// (here 0 or 1; without the test the run goes on to a third iteration).
TEST(DacpoIpsr, IterationThatTurnsNoSampleOverIsTheLast)
{
  for (size_t start : {0u, 1u}) {
    Cloud c = wavy_sheet(2500, 31);
    c.flip(0.0, 32);
    dacpo_ipsr_params prm;
    dacpo_ipsr_params_default(&prm);
    prm.settle_start = start;
    IpsrRun r;
    run(&c, prm, &r);
    EXPECT_EQ(r.stats.iterations, start + 1) << "settle_start " << start;
    EXPECT_TRUE(r.stats.converged);
    EXPECT_GE(r.stats.final_change, prm.convergence);
    EXPECT_EQ(c.wrong_percent(), 0.0);
  }
  Cloud u = wavy_sheet(2500, 31);
  u.flip(0.0, 32);
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  prm.settle_start = prm.max_iterations; // the sign test off
  IpsrRun ru;
  run(&u, prm, &ru);
  EXPECT_GT(ru.stats.iterations, 2u);
}

// "Few": an iteration from settle_start on that turns over no more samples
// than the convergence test averages (max(10, n / 1000)) ends the block. A
// sheet with 4 of 2500 normals flipped is put right by one iteration and stops
// there (settle_start = 0); with 120 flipped the first iteration turns too
// many and the run goes on.
TEST(DacpoIpsr, IterationThatTurnsFewSamplesOverIsTheLast)
{
  for (double share : {0.0016, 0.048}) {
    Cloud c = wavy_sheet(2500, 41);
    c.flip(share, 42);
    const double before = c.wrong_percent();
    ASSERT_GT(before, 0.0);
    dacpo_ipsr_params prm;
    dacpo_ipsr_params_default(&prm);
    prm.settle_start = 0;
    IpsrRun r;
    run(&c, prm, &r);
    EXPECT_EQ(c.wrong_percent(), 0.0) << "share " << share;
    EXPECT_TRUE(r.stats.converged);
    if (before * 25.0 <= 10.0) // at most 10 of 2500 flipped
      EXPECT_EQ(r.stats.iterations, 1u) << "share " << share;
    else
      EXPECT_GT(r.stats.iterations, 1u) << "share " << share;
  }
}

TEST(DacpoIpsr, HalfCylinderWithFlippedNormalsConverges)
{
  Cloud c = half_cylinder(2500, 21);
  c.flip(0.3, 22);
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  IpsrRun r;
  run(&c, prm, &r);
  EXPECT_LT(c.wrong_percent(), 1.0);
  EXPECT_TRUE(r.stats.converged);
}

// A 2 cm board sampled at 1 cm: the two big faces must stay opposite (no
// averaging across the thin solid), even from partly flipped normals.
TEST(DacpoIpsr, ThinBoardKeepsItsTwoSidesOpposite)
{
  for (double share : {0.0, 0.2}) {
    Cloud c = thin_board(31);
    c.flip(share, 32);
    dacpo_ipsr_params prm;
    dacpo_ipsr_params_default(&prm);
    IpsrRun r;
    run(&c, prm, &r);
    size_t top_wrong = 0, bottom_wrong = 0, top = 0, bottom = 0;
    for (size_t i = 0; i < c.size(); ++i) {
      if (std::fabs(c.gt[3 * i + 2]) < 0.5)
        continue;
      bool wrong = c.n[3 * i + 2] * c.gt[3 * i + 2] < 0;
      if (c.gt[3 * i + 2] > 0)
        ++top, top_wrong += wrong;
      else
        ++bottom, bottom_wrong += wrong;
    }
    EXPECT_LT(100.0 * top_wrong / top, 1.0) << "flipped share " << share;
    EXPECT_LT(100.0 * bottom_wrong / bottom, 1.0) << "flipped share " << share;
    EXPECT_LT(c.wrong_percent(), 2.0) << "flipped share " << share;
  }
}

struct HoleCounts {
  size_t outside = 0; // beyond the patch by more than the trimming distance + a cell
  size_t in_hole = 0; // over the big hole, farther than that from its rim
  size_t in_gap = 0;  // over the small gap
};

HoleCounts
count_hole_faces(const IpsrRun& r, double far, double hole, double gap)
{
  HoleCounts h;
  for (size_t f = 0; f < r.mesh.num_triangles; ++f) {
    double q[3];
    centroid(r.mesh, f, q);
    double ex = std::max(std::fabs(q[0]), std::fabs(q[1])) - 1.0;
    h.outside += ex > far + r.stats.cell;
    h.in_hole += std::sqrt(q[0] * q[0] + q[1] * q[1]) < hole - far - r.stats.cell;
    h.in_gap += std::hypot(q[0] - 0.6, q[1] - 0.6) < 0.5 * gap;
  }
  return h;
}

// Default (narrow band): the surface stops a few cells past the data, the
// trimming removes what runs on past the patch's rim, a hole wider than the
// band stays open, and a gap narrower than the trimming distance stays
// covered (interior gaps are not punched).
TEST(DacpoIpsr, FixedSamplesKeepTheirNormals)
{
  // 30 % of the wavy sheet's normals flipped; half of those flipped points are
  // fixed: they must come out exactly as given, the free ones repaired.
  Cloud c = wavy_sheet(2500, 13);
  c.flip(0.3, 14);
  const std::vector<double> given = c.n;
  std::vector<uint8_t> fixed(c.size(), 0);
  size_t fixed_wrong = 0;
  for (size_t i = 0; i < c.size(); i += 2)
    if (c.n[3 * i] * c.gt[3 * i] + c.n[3 * i + 1] * c.gt[3 * i + 1] +
            c.n[3 * i + 2] * c.gt[3 * i + 2] <
        0.0) {
      fixed[i] = 1;
      ++fixed_wrong;
    }
  ASSERT_GT(fixed_wrong, 100u);
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  prm.fixed = fixed.data();
  IpsrRun r;
  run(&c, prm, &r);
  size_t free_wrong = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    if (fixed[i]) {
      for (int d = 0; d < 3; ++d)
        EXPECT_EQ(c.n[3 * i + d], given[3 * i + d]) << "fixed sample " << i;
      continue;
    }
    free_wrong += c.n[3 * i] * c.gt[3 * i] + c.n[3 * i + 1] * c.gt[3 * i + 1] +
                      c.n[3 * i + 2] * c.gt[3 * i + 2] <
                  0.0;
  }
  EXPECT_LT(100.0 * free_wrong / (c.size() - fixed_wrong), 1.0);
}

TEST(DacpoIpsr, TrimmingRemovesWingsKeepsHolesAndCoversGaps)
{
  const double step = 0.04, hole = 0.35, gap = 2 * step;
  Cloud c = holed_plane(step, hole, gap, 41);
  c.n = c.gt;
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  IpsrRun r;
  run(&c, prm, &r);
  ASSERT_GT(r.mesh.num_triangles, 1000u);
  HoleCounts h = count_hole_faces(r, prm.trim_spacings * r.stats.spacing, hole, gap);
  EXPECT_EQ(h.outside, 0u);
  EXPECT_EQ(h.in_hole, 0u);
  EXPECT_GT(h.in_gap, 4u);
  EXPECT_LT(c.wrong_percent(), 0.5);
}

// With a wide band the Neumann surface spans the big hole as a film and runs
// on past the rim as wings. The wings are trimmed (far faces joined to the
// mesh rim); the film is joined to the rim only through faces near the data,
// so it stays; trim_interior removes it too.
TEST(DacpoIpsr, TrimmingFloodsFromTheRimOnly)
{
  const double step = 0.04, hole = 0.35, gap = 2 * step;
  for (int interior : {0, 1}) {
    Cloud c = holed_plane(step, hole, gap, 42);
    c.n = c.gt;
    dacpo_ipsr_params prm;
    dacpo_ipsr_params_default(&prm);
    prm.band = 12;
    prm.experiment.trim_interior = interior;
    IpsrRun r;
    run(&c, prm, &r);
    HoleCounts h = count_hole_faces(r, prm.trim_spacings * r.stats.spacing, hole, gap);
    EXPECT_EQ(h.outside, 0u) << "trim_interior " << interior;
    if (interior)
      EXPECT_EQ(h.in_hole, 0u);
    else
      EXPECT_GT(h.in_hole, 50u);
    EXPECT_GT(h.in_gap, 4u) << "trim_interior " << interior;
    EXPECT_LT(c.wrong_percent(), 0.5);
  }
  // Without trimming (trim_start beyond the run, trim distance huge) the
  // wings are there: the check above can fail.
  Cloud c = holed_plane(step, hole, gap, 43);
  c.n = c.gt;
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  prm.band = 12;
  prm.trim_spacings = 1e6;
  IpsrRun r;
  run(&c, prm, &r);
  EXPECT_GT(count_hole_faces(r, 2.5 * r.stats.spacing, hole, gap).outside, 100u);
}

// A foreground patch 0.3 (7.5 cells) in front of a background plane, both facing +z, as
// a depth scan sees an object before a wall. A Poisson indicator cannot step up twice
// with one iso-value: over the whole box the two sheets fight through the free space
// between them and the front one flips. In the narrow band (default) each sheet's
// neighbourhood is its own domain and both keep their orientation; this is why the band
// is the default.
TEST(DacpoIpsr, StackedSheetsOfADepthScanKeepTheirOrientation)
{
  auto make = []() {
    Cloud c;
    const double step = 0.04;
    for (double y = -1; y <= 1 + 1e-9; y += step)
      for (double x = -1; x <= 1 + 1e-9; x += step)
        c.add(x, y, 0.0, 0, 0, 1);
    for (double y = -0.5; y <= 0.5 + 1e-9; y += step)
      for (double x = -0.5; x <= 0.5 + 1e-9; x += step)
        c.add(x + 0.013, y + 0.007, 0.3, 0, 0, 1);
    c.n = c.gt;
    return c;
  };
  Cloud band = make();
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  IpsrRun r;
  run(&band, prm, &r);
  EXPECT_EQ(band.wrong_percent(), 0.0);
  Cloud box = make();
  prm.band = 0; // the whole box
  IpsrRun rb;
  run(&box, prm, &rb);
  EXPECT_GT(box.wrong_percent(), 5.0);
}

// After trimming, no face of an open sheet is far from the data: the check
// that Neumann iPSR leaves no space-closing faces behind.
TEST(DacpoIpsr, TrimmedMeshStaysNearTheData)
{
  Cloud c = half_cylinder(2500, 51);
  c.flip(0.3, 52);
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  IpsrRun r;
  run(&c, prm, &r);
  ASSERT_GT(r.mesh.num_triangles, 1000u);
  dacpo_kdtree* tree = nullptr;
  dacpo_err err{};
  ASSERT_EQ(dacpo_kdtree_build(c.p.data(), c.size(), &tree, &err), DACPO_OK);
  const double far = prm.trim_spacings * r.stats.spacing + r.stats.cell;
  size_t far_faces = 0;
  for (size_t f = 0; f < r.mesh.num_triangles; ++f) {
    double q[3], d2;
    int32_t idx;
    centroid(r.mesh, f, q);
    dacpo_kdtree_knn(tree, q, 1, &idx, &d2);
    far_faces += std::sqrt(d2) > far;
  }
  dacpo_kdtree_free(tree);
  EXPECT_EQ(far_faces, 0u);
}

// The block mesh covers only the own points (the first n_own), and its
// winding agrees with the refined normals.
TEST(DacpoIpsr, MeshOutCoversOwnPointsAndAgreesWithNormals)
{
  Cloud all = wavy_sheet(3000, 61);
  // own points: x < 0.3; ring: the rest, stored after them
  Cloud c;
  std::vector<size_t> order;
  for (size_t i = 0; i < all.size(); ++i)
    if (all.p[3 * i] < 0.3)
      order.push_back(i);
  const size_t n_own = order.size();
  for (size_t i = 0; i < all.size(); ++i)
    if (all.p[3 * i] >= 0.3)
      order.push_back(i);
  for (size_t i : order)
    c.add(all.p[3 * i],
          all.p[3 * i + 1],
          all.p[3 * i + 2],
          all.gt[3 * i],
          all.gt[3 * i + 1],
          all.gt[3 * i + 2]);
  c.flip(0.2, 62);
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  IpsrRun r;
  run(&c, prm, &r, n_own);
  ASSERT_GT(r.mesh.num_triangles, 500u);
  dacpo_kdtree* tree = nullptr;
  dacpo_err err{};
  ASSERT_EQ(dacpo_kdtree_build(c.p.data(), c.size(), &tree, &err), DACPO_OK);
  size_t ring = 0, agree = 0;
  double xmax = -1e9;
  std::vector<char> used(r.mesh.num_vertices, 0);
  for (size_t f = 0; f < r.mesh.num_triangles; ++f) {
    const int32_t* t = r.mesh.triangles + 3 * f;
    for (int k = 0; k < 3; ++k) {
      ASSERT_GE(t[k], 0);
      ASSERT_LT((size_t)t[k], r.mesh.num_vertices);
      used[t[k]] = 1;
    }
    double q[3], d2;
    int32_t idx;
    centroid(r.mesh, f, q);
    xmax = std::max(xmax, q[0]);
    dacpo_kdtree_knn(tree, q, 1, &idx, &d2);
    ring += (size_t)idx >= n_own;
    const double* a = r.mesh.vertices + 3 * t[0];
    const double* b = r.mesh.vertices + 3 * t[1];
    const double* d = r.mesh.vertices + 3 * t[2];
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double e2[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    double nz[3] = {e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0]};
    const double* sn = c.n.data() + 3 * idx;
    agree += nz[0] * sn[0] + nz[1] * sn[1] + nz[2] * sn[2] > 0;
  }
  dacpo_kdtree_free(tree);
  EXPECT_EQ(ring, 0u);
  EXPECT_LT(xmax, 0.3 + 2 * r.stats.cell);
  EXPECT_GT(agree, r.mesh.num_triangles * 98 / 100);
  for (size_t v = 0; v < r.mesh.num_vertices; ++v)
    ASSERT_TRUE(used[v]) << "vertex " << v << " unused (not compacted)";
  EXPECT_LT(c.wrong_percent(), 1.0);
}

TEST(DacpoIpsr, ZeroIterationsKeepsNormalsAndStillGivesAMesh)
{
  Cloud c = wavy_sheet(1500, 71);
  c.flip(0.3, 72);
  std::vector<double> before = c.n;
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  prm.max_iterations = 0;
  IpsrRun r;
  run(&c, prm, &r);
  EXPECT_EQ(c.n, before);
  EXPECT_EQ(r.stats.iterations, 0u);
  EXPECT_GT(r.mesh.num_triangles, 0u);
}

TEST(DacpoIpsr, StopsAtMaxIterationsAndIsDeterministic)
{
  Cloud a = half_cylinder(1500, 81);
  a.flip(0.4, 82);
  Cloud b = a;
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  prm.max_iterations = 2;
  IpsrRun ra, rb;
  run(&a, prm, &ra);
  run(&b, prm, &rb);
  EXPECT_EQ(ra.stats.iterations, 2u);
  EXPECT_FALSE(ra.stats.converged);
  EXPECT_EQ(a.n, b.n);
  EXPECT_EQ(ra.mesh.num_triangles, rb.mesh.num_triangles);
}

TEST(DacpoIpsr, RejectsBadInput)
{
  Cloud c = wavy_sheet(200, 91);
  c.n = c.gt;
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  dacpo_ipsr_stats st;
  dacpo_err err{};
  EXPECT_EQ(
      dacpo_ipsr_block(c.p.data(), c.n.data(), 200, 201, &prm, nullptr, &st, &err),
      DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(
      dacpo_ipsr_block(c.p.data(), c.n.data(), 200, 200, nullptr, nullptr, &st, &err),
      DACPO_ERR_INVALID_ARGUMENT);
  dacpo_ipsr_params bad = prm;
  bad.face_k = 0;
  EXPECT_EQ(
      dacpo_ipsr_block(c.p.data(), c.n.data(), 200, 200, &bad, nullptr, &st, &err),
      DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(err.msg).find("face_k"), std::string::npos);
  bad = prm;
  bad.cell_per_spacing = 0;
  EXPECT_EQ(
      dacpo_ipsr_block(c.p.data(), c.n.data(), 200, 200, &bad, nullptr, &st, &err),
      DACPO_ERR_INVALID_ARGUMENT);
  std::vector<double> nan_n = c.n;
  nan_n[3 * 17] = NAN;
  EXPECT_EQ(
      dacpo_ipsr_block(c.p.data(), nan_n.data(), 200, 200, &prm, nullptr, &st, &err),
      DACPO_ERR_NONFINITE_INPUT);
  EXPECT_NE(std::string(err.msg).find("17"), std::string::npos);
  // tiny blocks are left alone
  EXPECT_EQ(dacpo_ipsr_block(c.p.data(), c.n.data(), 3, 3, &prm, nullptr, &st, &err),
            DACPO_OK);
  EXPECT_EQ(st.iterations, 0u);
  EXPECT_EQ(dacpo_ipsr_block(nullptr, nullptr, 0, 0, &prm, nullptr, &st, &err),
            DACPO_OK);
}

// Degenerate blocks (coincident points, a line, zero normals) run without
// error and leave finite unit or unchanged normals.
TEST(DacpoIpsr, DegenerateBlocksStayFinite)
{
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  for (int kind = 0; kind < 3; ++kind) {
    Cloud c;
    for (int i = 0; i < 300; ++i) {
      if (kind == 0)
        c.add(1, 2, 3, 0, 0, 1); // all coincident
      else if (kind == 1)
        c.add(0.01 * i, 0.02 * i, -0.01 * i, 0, 1, 0); // a line
      else
        c.add(0.05 * (i % 20), 0.05 * (i / 20), 0, 0, 0, 1); // a plane ...
    }
    c.n = c.gt;
    if (kind == 2)
      for (int i = 0; i < 300; i += 3)
        c.n[3 * i] = c.n[3 * i + 1] = c.n[3 * i + 2] = 0; // ... a third without normals
    IpsrRun r;
    run(&c, prm, &r);
    for (size_t i = 0; i < c.size(); ++i) {
      double l = std::sqrt(c.n[3 * i] * c.n[3 * i] + c.n[3 * i + 1] * c.n[3 * i + 1] +
                           c.n[3 * i + 2] * c.n[3 * i + 2]);
      ASSERT_TRUE(std::isfinite(l)) << "kind " << kind << " point " << i;
      ASSERT_TRUE(l == 0.0 || std::fabs(l - 1.0) < 1e-9) << "kind " << kind;
    }
    if (kind == 2) { // the plane's normals are all restored, +z
      EXPECT_EQ(c.wrong_percent(), 0.0);
      for (size_t i = 0; i < c.size(); ++i)
        EXPECT_GT(c.n[3 * i + 2], 0.9);
    }
  }
}
