// SPDX-License-Identifier: BSD-3-Clause
// Screened Poisson solver with Neumann boundary (stage 3, dacpo_poisson.c):
// closed shapes are reconstructed within a cell with agreeing normals; open
// sheets split space into two sides without any space-closing faces.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

extern "C" {
#include "dacpo_mcubes.h"
#include "dacpo_poisson.h"
#include "mcubes_once.hpp"
}

namespace {

const double kPi = 3.14159265358979323846;

struct Samples {
  std::vector<double> p, n;
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
    n.insert(n.end(), {nx / l, ny / l, nz / l});
  }
};

Samples
sphere(size_t count, double r, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Samples s;
  for (size_t i = 0; i < count; ++i) {
    double z = 2 * U(rng) - 1, ph = 2 * kPi * U(rng), q = std::sqrt(1 - z * z);
    s.add(r * q * std::cos(ph),
          r * q * std::sin(ph),
          r * z,
          q * std::cos(ph),
          q * std::sin(ph),
          z);
  }
  return s;
}

// Surface of [-1, 1]^3, uniform by area, outward normals.
Samples
cube(size_t count, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::uniform_int_distribution<int> F(0, 5);
  Samples s;
  for (size_t i = 0; i < count; ++i) {
    int f = F(rng), a = f / 2;
    double sg = f % 2 ? -1.0 : 1.0;
    double q[3] = {U(rng), U(rng), U(rng)}, nn[3] = {0, 0, 0};
    q[a] = sg;
    nn[a] = sg;
    s.add(q[0], q[1], q[2], nn[0], nn[1], nn[2]);
  }
  return s;
}

// Grid-like sampling of the square [-1, 1]^2 in z = 0 with jitter, normal +z.
Samples
plane_patch(double step, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> J(-0.3 * step, 0.3 * step);
  Samples s;
  for (double y = -1; y <= 1 + 1e-9; y += step)
    for (double x = -1; x <= 1 + 1e-9; x += step)
      s.add(x + J(rng), y + J(rng), 0.0, 0, 0, 1);
  return s;
}

// Half cylinder: radius 1, axis y in [-1, 1], z >= 0, outward normals.
Samples
half_cylinder(size_t count, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Samples s;
  for (size_t i = 0; i < count; ++i) {
    double t = kPi * U(rng), y = 2 * U(rng) - 1;
    s.add(std::cos(t), y, std::sin(t), std::cos(t), 0, std::sin(t));
  }
  return s;
}

struct Solved {
  dacpo_poisson* ps = nullptr;
  dacpo_mesh mesh{};
  dacpo_poisson_info info{};
  ~Solved()
  {
    dacpo_poisson_free(ps);
    dacpo_mesh_free(&mesh);
  }
};

void
solve(const Samples& s, double spacing, Solved* out, double cell_per_spacing = 1.0)
{
  dacpo_poisson_params prm;
  dacpo_poisson_params_default(&prm);
  prm.cell_per_spacing = cell_per_spacing;
  dacpo_err err{};
  ASSERT_EQ(dacpo_poisson_create(
                s.p.data(), nullptr, s.size(), spacing, &prm, &out->ps, &err),
            DACPO_OK)
      << err.msg;
  ASSERT_EQ(dacpo_poisson_solve(out->ps, s.n.data(), &out->info, &err), DACPO_OK)
      << err.msg;
  ASSERT_EQ(mcubes_once(dacpo_poisson_grid(out->ps),
                        dacpo_poisson_values(out->ps),
                        dacpo_poisson_domain(out->ps),
                        out->info.iso_value,
                        &out->mesh,
                        &err),
            DACPO_OK)
      << err.msg;
  ASSERT_GT(out->mesh.num_triangles, 0u);
}

void
face(const dacpo_mesh& m, size_t f, double n[3], double c[3], double* area2)
{
  const int32_t* t = m.triangles + 3 * f;
  const double* a = m.vertices + 3 * t[0];
  const double* b = m.vertices + 3 * t[1];
  const double* d = m.vertices + 3 * t[2];
  double e1[3], e2[3];
  for (int k = 0; k < 3; ++k) {
    e1[k] = b[k] - a[k];
    e2[k] = d[k] - a[k];
    c[k] = (a[k] + b[k] + d[k]) / 3.0;
  }
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  *area2 = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

} // namespace

TEST(DacpoPoisson, SphereWithinOneCellAndNormalsAgree)
{
  const size_t count = 3000;
  Samples s = sphere(count, 1.0, 1);
  Solved r;
  solve(s, std::sqrt(4 * kPi / count), &r);
  const double h = dacpo_poisson_grid(r.ps)->cell;
  for (size_t v = 0; v < r.mesh.num_vertices; ++v) {
    const double* p = r.mesh.vertices + 3 * v;
    ASSERT_NEAR(std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), 1.0, h);
  }
  double cs = 0, wsum = 0;
  for (size_t f = 0; f < r.mesh.num_triangles; ++f) {
    double n[3], c[3], a;
    face(r.mesh, f, n, c, &a);
    if (a <= 0)
      continue;
    double lc = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    cs += (n[0] * c[0] + n[1] * c[1] + n[2] * c[2]) / lc;
    wsum += a;
  }
  EXPECT_GT(cs / wsum, 0.98);
  // chi grows along the normals: low inside, high outside, iso about 1/2
  // (three cells off the surface, inside the narrow-band domain).
  const double in[3] = {1 - 3 * h, 0, 0}, out[3] = {0, 0, 1 + 3 * h};
  EXPECT_LT(dacpo_poisson_evaluate(r.ps, in), r.info.iso_value - 0.3);
  EXPECT_GT(dacpo_poisson_evaluate(r.ps, out), r.info.iso_value + 0.3);
  EXPECT_NEAR(r.info.iso_value, 0.5, 0.1);
  EXPECT_LE(r.info.residual, 1e-3);
}

TEST(DacpoPoisson, CubeWithinOneCellAndNormalsAgree)
{
  const size_t count = 4000;
  Samples s = cube(count, 2);
  Solved r;
  solve(s, std::sqrt(24.0 / count), &r);
  const double h = dacpo_poisson_grid(r.ps)->cell;
  // Distance to the cube's surface, measured in the max norm (exact inside,
  // a lower bound outside near edges and corners, where Poisson rounds).
  size_t near_half = 0;
  for (size_t v = 0; v < r.mesh.num_vertices; ++v) {
    const double* p = r.mesh.vertices + 3 * v;
    double m = std::max({std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])});
    ASSERT_NEAR(m, 1.0, h) << "vertex " << v;
    near_half += std::fabs(m - 1.0) < 0.5 * h;
  }
  EXPECT_GT(near_half, r.mesh.num_vertices * 9 / 10);
  double cs = 0, wsum = 0;
  for (size_t f = 0; f < r.mesh.num_triangles; ++f) {
    double n[3], c[3], a;
    face(r.mesh, f, n, c, &a);
    if (a <= 0)
      continue;
    // outward normal of the nearest cube face
    int ax = 0;
    for (int k = 1; k < 3; ++k)
      if (std::fabs(c[k]) > std::fabs(c[ax]))
        ax = k;
    cs += n[ax] * (c[ax] > 0 ? 1.0 : -1.0);
    wsum += a;
  }
  EXPECT_GT(cs / wsum, 0.9);
}

// Neumann: an open plane patch splits space into below/above and the surface
// simply runs on to the box walls in its own plane; nothing closes it (a
// Dirichlet solve would wrap a closed surface around the patch).
TEST(DacpoPoisson, PlanePatchSeparatesWithoutClosing)
{
  const double step = 0.04;
  Samples s = plane_patch(step, 3);
  Solved r;
  solve(s, step, &r);
  const double h = dacpo_poisson_grid(r.ps)->cell;
  const double above[3] = {0.1, -0.2, 3 * h}, below[3] = {0.1, -0.2, -3 * h};
  EXPECT_GT(dacpo_poisson_evaluate(r.ps, above), r.info.iso_value + 0.3);
  EXPECT_LT(dacpo_poisson_evaluate(r.ps, below), r.info.iso_value - 0.3);
  size_t far_from_plane = 0;
  double zmax = 0;
  for (size_t v = 0; v < r.mesh.num_vertices; ++v) {
    double z = std::fabs(r.mesh.vertices[3 * v + 2]);
    zmax = std::max(zmax, z);
    far_from_plane += z > 2 * h;
  }
  EXPECT_EQ(far_from_plane, 0u) << "max |z| " << zmax << " cell " << h;
  // All faces face up (+z, along the normals).
  for (size_t f = 0; f < r.mesh.num_triangles; ++f) {
    double n[3], c[3], a;
    face(r.mesh, f, n, c, &a);
    if (a > 1e-12 * h * h) {
      ASSERT_GT(n[2] / a, 0.7) << "face " << f;
    }
  }
}

// Half cylinder open at the bottom: inside and outside are told apart, the
// surface near the samples exists, and no face closes the opening (no faces
// under the arch between the rims, below the rim level).
TEST(DacpoPoisson, HalfCylinderSeparatesWithoutClosing)
{
  const size_t count = 2500;
  Samples s = half_cylinder(count, 4);
  const double spacing = std::sqrt(2 * kPi / count);
  Solved r;
  solve(s, spacing, &r);
  const double h = dacpo_poisson_grid(r.ps)->cell;
  const double inside[3] = {0, 0, 1 - 3 * h}, outside[3] = {0, 0, 1 + 3 * h};
  EXPECT_LT(dacpo_poisson_evaluate(r.ps, inside), r.info.iso_value - 0.2);
  EXPECT_GT(dacpo_poisson_evaluate(r.ps, outside), r.info.iso_value + 0.2);
  size_t closing = 0, on_arch = 0;
  for (size_t f = 0; f < r.mesh.num_triangles; ++f) {
    double n[3], c[3], a;
    face(r.mesh, f, n, c, &a);
    double rad = std::sqrt(c[0] * c[0] + c[2] * c[2]);
    if (std::fabs(c[0]) < 0.8 && c[2] < 0.5 && std::fabs(c[1]) < 1.0)
      ++closing; // a face across the mouth or inside the arch
    if (c[2] > 0.05 && std::fabs(rad - 1.0) < h)
      ++on_arch;
  }
  EXPECT_EQ(closing, 0u);
  EXPECT_GT(on_arch, r.mesh.num_triangles / 3);
  // Every sample has the surface within a cell.
  dacpo_err err{};
  (void)err;
  size_t far = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    double v = dacpo_poisson_evaluate(r.ps, &s.p[3 * i]) - r.info.iso_value;
    far += std::fabs(v) > 0.25;
  }
  EXPECT_LT(far, s.size() / 100);
}

// The narrow band gives the same surface near the data as the whole box: on a
// sphere, the band's iso-surface vertices lie on the box solution's
// iso-surface (within a tenth of the jump), and the band works on far fewer
// cells.
TEST(DacpoPoisson, NarrowBandMatchesWholeBoxNearTheData)
{
  const size_t count = 2500;
  Samples s = sphere(count, 1.0, 8);
  const double spacing = std::sqrt(4 * kPi / count);
  dacpo_poisson_params prm;
  dacpo_poisson_params_default(&prm);
  prm.tolerance = 1e-5;
  prm.max_cg_iterations = 200;
  dacpo_err err{};
  dacpo_poisson *band = nullptr, *box = nullptr;
  ASSERT_EQ(
      dacpo_poisson_create(s.p.data(), nullptr, count, spacing, &prm, &band, &err),
      DACPO_OK);
  prm.band = 0;
  ASSERT_EQ(dacpo_poisson_create(s.p.data(), nullptr, count, spacing, &prm, &box, &err),
            DACPO_OK);
  dacpo_poisson_info ib{}, ix{};
  ASSERT_EQ(dacpo_poisson_solve(band, s.n.data(), &ib, &err), DACPO_OK);
  ASSERT_EQ(dacpo_poisson_solve(box, s.n.data(), &ix, &err), DACPO_OK);
  EXPECT_LT(dacpo_poisson_domain_cells(band), dacpo_poisson_domain_cells(box) / 2);
  dacpo_mesh m{};
  ASSERT_EQ(mcubes_once(dacpo_poisson_grid(band),
                        dacpo_poisson_values(band),
                        dacpo_poisson_domain(band),
                        ib.iso_value,
                        &m,
                        &err),
            DACPO_OK);
  ASSERT_GT(m.num_vertices, 1000u);
  double worst = 0;
  for (size_t v = 0; v < m.num_vertices; ++v)
    worst = std::max(
        worst,
        std::fabs(dacpo_poisson_evaluate(box, m.vertices + 3 * v) - ix.iso_value));
  EXPECT_LT(worst, 0.05);
  dacpo_mesh_free(&m);
  dacpo_poisson_free(band);
  dacpo_poisson_free(box);
}

TEST(DacpoPoisson, WarmStartNeedsFewerIterations)
{
  const size_t count = 2000;
  Samples s = sphere(count, 1.0, 5);
  dacpo_poisson_params prm;
  dacpo_poisson_params_default(&prm);
  prm.tolerance = 1e-4;
  dacpo_poisson* ps = nullptr;
  dacpo_err err{};
  ASSERT_EQ(
      dacpo_poisson_create(
          s.p.data(), nullptr, count, std::sqrt(4 * kPi / count), &prm, &ps, &err),
      DACPO_OK);
  dacpo_poisson_info cold{}, same{}, near{};
  ASSERT_EQ(dacpo_poisson_solve(ps, s.n.data(), &cold, &err), DACPO_OK);
  EXPECT_GE(cold.iterations, 1u);
  EXPECT_LE(cold.residual, 1e-4);
  ASSERT_EQ(dacpo_poisson_solve(ps, s.n.data(), &same, &err), DACPO_OK);
  EXPECT_EQ(same.iterations, 0u); // already solved
  // A small change of the normals (as late in iPSR) costs at most as much.
  std::vector<double> n2 = s.n;
  for (size_t i = 0; i < count; i += 50)
    for (int a = 0; a < 3; ++a)
      n2[3 * i + a] = -n2[3 * i + a];
  ASSERT_EQ(dacpo_poisson_solve(ps, n2.data(), &near, &err), DACPO_OK);
  EXPECT_LE(near.iterations, cold.iterations);
  EXPECT_LE(near.residual, 1e-4);
  EXPECT_GT(dacpo_poisson_bytes(ps), 0u);
  dacpo_poisson_free(ps);
}

TEST(DacpoPoisson, GridFollowsSpacingAndCaps)
{
  Samples s = plane_patch(0.05, 6); // 2 x 2 patch, flat in z
  dacpo_poisson_params prm;
  dacpo_poisson_params_default(&prm);
  dacpo_err err{};
  dacpo_poisson* ps = nullptr;
  ASSERT_EQ(dacpo_poisson_create(s.p.data(), nullptr, s.size(), 0.05, &prm, &ps, &err),
            DACPO_OK);
  const dacpo_grid* g = dacpo_poisson_grid(ps);
  EXPECT_DOUBLE_EQ(g->cell, 0.05);
  EXPECT_GE(g->dims[0] * g->cell, 2.4); // padded by >= 10 % of 2 on each side
  EXPECT_LT(g->dims[2], g->dims[0]);    // the box is not forced to a cube
  for (int a = 0; a < 3; ++a) {         // samples are at least two cells inside
    EXPECT_LE(g->origin[a] + 2 * g->cell, a < 2 ? -1.0 : 0.0);
    EXPECT_GE(g->origin[a] + (g->dims[a] - 2) * g->cell, a < 2 ? 1.0 : 0.0);
  }
  dacpo_poisson_free(ps);
  prm.max_resolution = 32;
  ASSERT_EQ(dacpo_poisson_create(s.p.data(), nullptr, s.size(), 0.05, &prm, &ps, &err),
            DACPO_OK);
  g = dacpo_poisson_grid(ps);
  EXPECT_LE(std::max({g->dims[0], g->dims[1], g->dims[2]}), 32u);
  EXPECT_GT(g->cell, 0.05);
  dacpo_poisson_free(ps);
  prm.max_resolution = 128;
  prm.max_cells = 4096;
  ASSERT_EQ(dacpo_poisson_create(s.p.data(), nullptr, s.size(), 0.05, &prm, &ps, &err),
            DACPO_OK);
  g = dacpo_poisson_grid(ps);
  EXPECT_LE(g->dims[0] * g->dims[1] * g->dims[2], 4096u);
  dacpo_poisson_free(ps);
}

TEST(DacpoPoisson, RejectsBadArguments)
{
  Samples s = sphere(100, 1.0, 7);
  dacpo_poisson_params prm;
  dacpo_poisson_params_default(&prm);
  dacpo_poisson* ps = nullptr;
  dacpo_err err{};
  EXPECT_EQ(dacpo_poisson_create(s.p.data(), nullptr, 0, 0.1, &prm, &ps, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_poisson_create(s.p.data(), nullptr, 100, 0.0, &prm, &ps, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_poisson_create(s.p.data(), nullptr, 100, NAN, &prm, &ps, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  std::vector<double> bad = s.p;
  bad[3 * 42 + 1] = INFINITY;
  EXPECT_EQ(dacpo_poisson_create(bad.data(), nullptr, 100, 0.1, &prm, &ps, &err),
            DACPO_ERR_NONFINITE_INPUT);
  EXPECT_NE(std::string(err.msg).find("42"), std::string::npos);
  prm.point_weight = -1;
  EXPECT_EQ(dacpo_poisson_create(s.p.data(), nullptr, 100, 0.1, &prm, &ps, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(ps, nullptr);
  EXPECT_EQ(dacpo_poisson_solve(nullptr, s.n.data(), nullptr, &err),
            DACPO_ERR_INVALID_ARGUMENT);
  dacpo_poisson_free(nullptr);
}

// A single point or coincident points still give a valid (tiny) grid.
TEST(DacpoPoisson, DegenerateSampleSets)
{
  const double p[6] = {1, 2, 3, 1, 2, 3}, n[6] = {0, 0, 1, 0, 0, 1};
  dacpo_poisson_params prm;
  dacpo_poisson_params_default(&prm);
  dacpo_poisson* ps = nullptr;
  dacpo_err err{};
  ASSERT_EQ(dacpo_poisson_create(p, nullptr, 2, 0.1, &prm, &ps, &err), DACPO_OK)
      << err.msg;
  dacpo_poisson_info info{};
  EXPECT_EQ(dacpo_poisson_solve(ps, n, &info, &err), DACPO_OK);
  EXPECT_TRUE(std::isfinite(info.iso_value));
  dacpo_poisson_free(ps);
}
