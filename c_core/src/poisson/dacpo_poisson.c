/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 3a: screened Poisson indicator with Neumann boundary conditions.
 *
 * Paper step: §4.3 ("iPSR Adaption") replaces the Dirichlet screened Poisson
 * reconstruction of iPSR by its Neumann variant (Kazhdan & Hoppe 2013): the
 * indicator chi minimises
 *     E(chi) = integral |grad chi - V|^2 + alpha * sum_s w_s (chi(p_s) - 1/2)^2
 * with no condition on the domain's boundary (the natural, zero-flux Neumann
 * condition). The Laplacian alone is singular (constants); the screening term
 * makes the system SPD.
 *
 * Discretisation: finite volumes on a regular grid of cubic cells, chi at cell
 * centres. The gradient lives on the faces between two cells of the domain (a
 * staggered grid), so the energy is sum_f (chi_b - chi_a - V_f)^2 in cell
 * units: its normal equations are the 7-point graph Laplacian of the domain's
 * cells, with faces to cells outside the domain simply absent (that IS the
 * Neumann condition), the divergence of the face-splatted V on the right, and
 * alpha * S with S = sum_s w_s phi_s phi_s^T (trilinear weights phi_s of the 8
 * cell centres around p_s). V is splatted from the oriented samples with
 * trilinear weights, each sample carrying its area, so chi jumps by about 1
 * across the surface and grows along the normals (high in front, low behind).
 *
 * Domain: the grid covers the block's padded box; the unknowns are the cells
 * within `band` cells (Chebyshev) of a sample's stencil, a narrow band around the
 * data, with the Neumann condition on the band's boundary (band = 0 keeps the
 * whole box). Away from the data the Neumann field is flat and carries no
 * information, so the band gives the same surface near the samples at a cost
 * that grows with the block's area instead of its box's volume (blocks cut
 * from real scans have boxes that are mostly empty). Storage stays dense
 * (direct addressing); every kernel walks the domain as runs of cells along x.
 *
 * Solver: CG preconditioned by one multigrid V-cycle per step (cell-centred,
 * 2x coarsening; the coarse domain is the parents of the fine one plus the
 * samples' stencils; rediscretised Laplacian plus the screening re-splatted on
 * every level; trilinear prolongation, with corners outside the coarse domain
 * folded onto the parent, and its transpose as restriction; forward
 * Gauss-Seidel before and backward after, so the cycle is symmetric; the
 * coarsest level is solved by Jacobi-CG). The Polak-Ribiere form of beta keeps
 * CG robust to the slightly inexact coarse solve. Everything that depends only
 * on the sample positions (grid, domain, levels, screening stencils) is built
 * once by dacpo_poisson_create; a solve rebuilds the right-hand side and starts
 * from the previous chi, which is what makes iPSR iterations cheap.
 *
 * Cost: setup O(box cells + n); a solve O(domain cells) per CG step, a few
 * steps with a warm start. Memory about 25 bytes per box cell (float grids,
 * flags, row index) plus 108 bytes per screened cell. Failure modes:
 * OUT_OF_MEMORY, INVALID_ARGUMENT or NONFINITE_INPUT for bad parameters or
 * samples.
 */
#include "dacpo_poisson.h"
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "dacpo_poisson_internal.h"

void
dacpo_poisson_params_default(dacpo_poisson_params* p)
{
  if (!p)
    return;
  p->cell_per_spacing = 1.0;
  p->max_resolution = 128;
  p->max_cells = 1500000; /* about 27 bytes per cell: <= 41 MB of grids */
  p->padding = 0.1;
  p->point_weight = 16.0;
  p->tolerance = 1e-3;
  p->max_cg_iterations = 30;
  p->band = 2;
}

/* ------------------------------------------------------------------------ */
/* Allocation with byte accounting. */

static void*
ps_alloc(dacpo_poisson* ps, size_t count, size_t size, int zero)
{
  void* m = zero ? dacpo_calloc_array(count ? count : 1, size)
                 : dacpo_malloc_array(count ? count : 1, size);
  if (m)
    ps->bytes += (count ? count : 1) * size;
  return m;
}

void
dacpo_poisson_free(dacpo_poisson* ps)
{
  if (!ps)
    return;
  free(ps->u);
  free(ps->w);
  free(ps->area);
  free(ps->sc);
  free(ps->sw);
  for (size_t l = 0; l < ps->levels; ++l) {
    free(ps->lv[l].x);
    free(ps->lv[l].b);
    free(ps->lv[l].flags);
    free(ps->lv[l].runs);
    free(ps->lv[l].srow);
    free(ps->lv[l].sval);
  }
  free(ps->chi);
  free(ps->r);
  free(ps->z);
  free(ps->p);
  free(ps->q);
  free(ps->cr);
  free(ps->cp);
  free(ps->cq);
  free(ps->cz);
  free(ps->cdiag);
  free(ps);
}

/* ------------------------------------------------------------------------ */
/* Grid geometry. */

static size_t
round_up(size_t v, size_t m)
{
  return (v + m - 1) / m * m;
}

/* Number of levels for a longest side of `dmax` cells: the fewest such that
 * the coarsest level has at most DACPO_POISSON_COARSEST cells per axis after
 * every side is rounded up to a multiple of 2^(levels-1). */
static size_t
level_count(size_t dmax)
{
  size_t L = 1;
  while (L < DACPO_POISSON_MAX_LEVELS &&
         round_up(dmax, (size_t)1 << (L - 1)) / ((size_t)1 << (L - 1)) >
             DACPO_POISSON_COARSEST)
    ++L;
  return L;
}

/* Chooses cell size, dims and levels. Returns 0 if no feasible grid. */
static int
choose_grid(const double lo[3],
            const double hi[3],
            double spacing,
            const dacpo_poisson_params* prm,
            dacpo_grid* g,
            size_t* levels)
{
  double ext[3], emax = 0.0;
  for (int a = 0; a < 3; ++a) {
    ext[a] = hi[a] - lo[a];
    if (ext[a] > emax)
      emax = ext[a];
  }
  double h = prm->cell_per_spacing * spacing;
  if (emax <= 0.0)
    emax = h;
  for (int attempt = 0; attempt < 400; ++attempt) {
    /* Padding: two cells so that every sample's stencils stay inside the
     * box, plus the band; the whole-box domain (band 0) also gets a share of
     * the longest side, room for the Neumann surface to run on. */
    double pad =
        prm->band ? (double)(prm->band + 2) * h : prm->padding * emax + 2.0 * h;
    size_t d[3], dmax = 0;
    for (int a = 0; a < 3; ++a) {
      double c = ceil((ext[a] + 2.0 * pad) / h);
      if (!(c < 1e7))
        c = 1e7;
      d[a] = (size_t)c;
      if (d[a] < 2)
        d[a] = 2;
      if (d[a] > dmax)
        dmax = d[a];
    }
    size_t L = level_count(dmax);
    size_t m = (size_t)1 << (L - 1);
    size_t cells = 1;
    dmax = 0;
    for (int a = 0; a < 3; ++a) {
      d[a] = round_up(d[a], m);
      if (d[a] > dmax)
        dmax = d[a];
      cells *= d[a];
    }
    int ok_res = dmax <= prm->max_resolution ||
                 /* rounding may overshoot a cap that is not a multiple of m */
                 round_up(prm->max_resolution, m) == dmax;
    if (ok_res && cells <= prm->max_cells) {
      g->cell = h;
      for (int a = 0; a < 3; ++a) {
        g->dims[a] = d[a];
        g->origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * (double)d[a] * h;
      }
      *levels = L;
      return 1;
    }
    /* Grow the cell towards the binding cap. */
    double f = 1.02;
    if (dmax > prm->max_resolution)
      f = fmax(f, (double)dmax / (double)prm->max_resolution);
    if (cells > prm->max_cells)
      f = fmax(f, cbrt((double)cells / (double)prm->max_cells));
    h *= f;
  }
  return 0;
}

/* Cell-centre trilinear stencil of point u (level cell units) per axis: the
 * two cells lo/hi and the weight f of hi, clamped to the grid (a clamped
 * weight folds onto the border cell, the Neumann reflection). */
static void
stencil_axes(
    const size_t n[3], const double u[3], size_t lo[3], size_t hi[3], double f[3])
{
  for (int a = 0; a < 3; ++a) {
    double t = u[a] - 0.5;
    double fl = floor(t);
    long top = (long)n[a] - 1;
    long l = fl < -1.0 ? -1 : (fl > (double)top ? top : (long)fl);
    long h = l + 1;
    l = l < 0 ? 0 : (l > top ? top : l);
    h = h < 0 ? 0 : (h > top ? top : h);
    lo[a] = (size_t)l;
    hi[a] = (size_t)h;
    f[a] = t - fl;
    if (!(f[a] >= 0.0 && f[a] <= 1.0))
      f[a] = 0.0;
  }
}

/* The 8 cells and weights of the stencil, corner c = (bit0 x, bit1 y, bit2 z). */
static void
cell_stencil(const size_t n[3], const double u[3], int32_t cell[8], float wt[8])
{
  size_t i0[3], i1[3];
  double f[3];
  stencil_axes(n, u, i0, i1, f);
  for (int c = 0; c < 8; ++c) {
    size_t ix = (c & 1) ? i1[0] : i0[0];
    size_t iy = (c & 2) ? i1[1] : i0[1];
    size_t iz = (c & 4) ? i1[2] : i0[2];
    double w = ((c & 1) ? f[0] : 1.0 - f[0]) * ((c & 2) ? f[1] : 1.0 - f[1]) *
               ((c & 4) ? f[2] : 1.0 - f[2]);
    cell[c] = (int32_t)(ix + n[0] * (iy + n[1] * iz));
    wt[c] = (float)w;
  }
}

/* ------------------------------------------------------------------------ */
/* Domain. */

/* In-place dilation of a 0/1 mask by r cells along one axis (sliding count). */
static void
dilate_axis(uint8_t* m, const size_t n[3], int axis, size_t r, uint8_t* line)
{
  const size_t len = n[axis];
  const size_t stride = axis == 0 ? 1 : (axis == 1 ? n[0] : n[0] * n[1]);
  const size_t o1 = axis == 0 ? n[1] : n[0];
  const size_t o2 = axis == 2 ? n[1] : n[2];
  const size_t s1 = axis == 0 ? n[0] : 1;
  const size_t s2 = axis == 2 ? n[0] : n[0] * n[1];
  for (size_t b = 0; b < o2; ++b)
    for (size_t a = 0; a < o1; ++a) {
      uint8_t* p = m + a * s1 + b * s2;
      for (size_t t = 0; t < len; ++t)
        line[t] = p[t * stride];
      /* count of marked cells in the window [t - r, t + r] */
      size_t count = 0;
      for (size_t t = 0; t < len && t < r; ++t)
        count += line[t];
      for (size_t t = 0; t < len; ++t) {
        if (t + r < len)
          count += line[t + r];
        p[t * stride] = count > 0;
        if (t >= r)
          count -= line[t - r];
      }
    }
}

/* Neighbour flags and runs of a level whose flags hold 1 for domain cells. */
static dacpo_status
finish_domain(dacpo_poisson* ps, mg_level* L, dacpo_err* err)
{
  const size_t nx = L->n[0], ny = L->n[1], nz = L->n[2];
  size_t active = 0, nruns = 0;
  for (size_t k = 0; k < nz; ++k)
    for (size_t j = 0; j < ny; ++j) {
      const uint8_t* row = L->flags + nx * (j + ny * k);
      for (size_t i = 0; i < nx; ++i)
        if (row[i]) {
          ++active;
          if (i == 0 || !row[i - 1])
            ++nruns;
        }
    }
  L->active = active;
  L->runs = (mg_run*)ps_alloc(ps, nruns, sizeof(mg_run), 0);
  if (!L->runs)
    return DACPO_OOM(err);
  L->nruns = 0;
  for (size_t k = 0; k < nz; ++k)
    for (size_t j = 0; j < ny; ++j) {
      const size_t base = nx * (j + ny * k);
      uint8_t* row = L->flags + base;
      for (size_t i = 0; i < nx; ++i) {
        if (!row[i])
          continue;
        if (i == 0 || !row[i - 1]) {
          L->runs[L->nruns].base = base;
          L->runs[L->nruns].i0 = (uint32_t)i;
          L->nruns++;
        }
        L->runs[L->nruns - 1].i1 = (uint32_t)(i + 1);
        uint8_t f = F_IN;
        const uint8_t* c = row + i;
        if (i > 0 && c[-1])
          f |= 1;
        if (i + 1 < nx && c[1])
          f |= 2;
        if (j > 0 && c[-(ptrdiff_t)nx])
          f |= 4;
        if (j + 1 < ny && c[nx])
          f |= 8;
        if (k > 0 && c[-(ptrdiff_t)(nx * ny)])
          f |= 16;
        if (k + 1 < nz && c[nx * ny])
          f |= 32;
        row[i] = f;
      }
    }
  return DACPO_OK;
}

/* Level 0: cells within `band` cells of a sample's cell (all cells if 0). */
static dacpo_status
build_domain0(dacpo_poisson* ps, size_t band, dacpo_err* err)
{
  mg_level* L = &ps->lv[0];
  L->flags = (uint8_t*)ps_alloc(ps, L->cells, 1, 1);
  if (!L->flags)
    return DACPO_OOM(err);
  if (band == 0) {
    memset(L->flags, 1, L->cells);
    return finish_domain(ps, L, err);
  }
  /* At least two cells: the splat and screening stencils of every sample
   * reach one cell beyond its own. */
  if (band < 2)
    band = 2;
  /* Seeds: the cell-centre stencils, symmetric about each sample. */
  int32_t cell[8];
  float wt[8];
  for (size_t s = 0; s < ps->n; ++s) {
    cell_stencil(L->n, ps->u + 3 * s, cell, wt);
    for (int c = 0; c < 8; ++c)
      L->flags[cell[c]] = 1;
  }
  size_t lmax = L->n[0] > L->n[1] ? L->n[0] : L->n[1];
  if (L->n[2] > lmax)
    lmax = L->n[2];
  uint8_t* line = (uint8_t*)malloc(lmax);
  if (!line)
    return DACPO_OOM(err);
  for (int a = 0; a < 3; ++a)
    dilate_axis(L->flags, L->n, a, band, line);
  free(line);
  return finish_domain(ps, L, err);
}

/* Level l >= 1: parents of the finer domain, plus the samples' stencils. */
static dacpo_status
build_domain_coarse(dacpo_poisson* ps, size_t l, dacpo_err* err)
{
  mg_level* L = &ps->lv[l];
  const mg_level* F = &ps->lv[l - 1];
  L->flags = (uint8_t*)ps_alloc(ps, L->cells, 1, 1);
  if (!L->flags)
    return DACPO_OOM(err);
  for (size_t r = 0; r < F->nruns; ++r) {
    const mg_run* run = &F->runs[r];
    size_t j = (run->base / F->n[0]) % F->n[1], k = run->base / (F->n[0] * F->n[1]);
    size_t cb = L->n[0] * ((j >> 1) + L->n[1] * (k >> 1));
    for (size_t i = run->i0; i < run->i1; ++i)
      L->flags[cb + (i >> 1)] = 1;
  }
  const double scale = 1.0 / (double)((size_t)1 << l);
  int32_t cell[8];
  float wt[8];
  for (size_t s = 0; s < ps->n; ++s) {
    double u[3] = {
        ps->u[3 * s] * scale, ps->u[3 * s + 1] * scale, ps->u[3 * s + 2] * scale};
    cell_stencil(L->n, u, cell, wt);
    for (int c = 0; c < 8; ++c)
      L->flags[cell[c]] = 1;
  }
  return finish_domain(ps, L, err);
}

/* Builds the screening rows of one level: S = sum_s w_s phi_s phi_s^T. */
static dacpo_status
build_screening(dacpo_poisson* ps, mg_level* L, double scale, dacpo_err* err)
{
  L->srow = (int32_t*)ps_alloc(ps, L->cells, sizeof(int32_t), 0);
  if (!L->srow)
    return DACPO_OOM(err);
  for (size_t i = 0; i < L->cells; ++i)
    L->srow[i] = -1;
  size_t rows = 0;
  int32_t cell[8];
  float wt[8];
  for (size_t s = 0; s < ps->n; ++s) {
    double u[3] = {
        ps->u[3 * s] * scale, ps->u[3 * s + 1] * scale, ps->u[3 * s + 2] * scale};
    cell_stencil(L->n, u, cell, wt);
    for (int c = 0; c < 8; ++c)
      if (L->srow[cell[c]] < 0)
        L->srow[cell[c]] = (int32_t)rows++;
  }
  L->rows = rows;
  L->sval = (float*)ps_alloc(ps, rows * 27, sizeof(float), 1);
  if (!L->sval)
    return DACPO_OOM(err);
  for (size_t s = 0; s < ps->n; ++s) {
    double u[3] = {
        ps->u[3 * s] * scale, ps->u[3 * s + 1] * scale, ps->u[3 * s + 2] * scale};
    size_t i0[3], i1[3];
    double f[3];
    stencil_axes(L->n, u, i0, i1, f);
    cell_stencil(L->n, u, cell, wt);
    const double ws = ps->w[s];
    for (int a = 0; a < 8; ++a) {
      if (wt[a] == 0.0f)
        continue;
      float* row = L->sval + 27 * (size_t)L->srow[cell[a]];
      for (int b = 0; b < 8; ++b) {
        if (wt[b] == 0.0f)
          continue;
        int o = 13;
        for (int e = 0, step = 1; e < 3; ++e, step *= 3) {
          long pa = (long)((a >> e) & 1 ? i1[e] : i0[e]);
          long pb = (long)((b >> e) & 1 ? i1[e] : i0[e]);
          o += (int)(pb - pa) * step;
        }
        row[o] += (float)(ws * (double)wt[a] * (double)wt[b]);
      }
    }
  }
  return DACPO_OK;
}

/* ------------------------------------------------------------------------ */

/* The parameters dacpo_poisson_create accepts. */
static dacpo_status
ps_check_params(double spacing, const dacpo_poisson_params* params, dacpo_err* err)
{
  DACPO_CHECK(err,
              isfinite(spacing) && spacing > 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "poisson: spacing must be finite and > 0 (got %g)",
              spacing);
  DACPO_CHECK(err,
              isfinite(params->cell_per_spacing) && params->cell_per_spacing > 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "poisson: cell_per_spacing must be > 0 (got %g)",
              params->cell_per_spacing);
  DACPO_CHECK(err,
              params->max_resolution >= 4 && params->max_resolution <= 4096,
              DACPO_ERR_INVALID_ARGUMENT,
              "poisson: max_resolution must be in [4, 4096] (got %zu)",
              params->max_resolution);
  DACPO_CHECK(err,
              params->max_cells >= 64 && params->max_cells <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "poisson: max_cells must be in [64, 2^31) (got %zu)",
              params->max_cells);
  DACPO_CHECK(err,
              isfinite(params->padding) && params->padding >= 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "poisson: padding must be >= 0 (got %g)",
              params->padding);
  DACPO_CHECK(err,
              isfinite(params->point_weight) && params->point_weight > 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "poisson: point_weight must be > 0 (got %g)",
              params->point_weight);
  DACPO_CHECK(err,
              isfinite(params->tolerance) && params->tolerance > 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "poisson: tolerance must be > 0 (got %g)",
              params->tolerance);
  DACPO_CHECK(err,
              params->band <= 256,
              DACPO_ERR_INVALID_ARGUMENT,
              "poisson: band must be <= 256 cells (got %zu)",
              params->band);

  return DACPO_OK;
}

/* Samples in cell units and their screening weights alpha * area (areas
 * relative to a cell face; all-zero areas fall back to uniform ones). */
static void
ps_set_samples(dacpo_poisson* ps,
               const double* xyz,
               const double* area,
               size_t n,
               double spacing,
               double alpha)
{
  const dacpo_grid* g = &ps->grid;
  const double h = g->cell;
  ps->wsum = 0.0;
  for (size_t s = 0; s < n; ++s) {
    for (int a = 0; a < 3; ++a)
      ps->u[3 * s + a] = (xyz[3 * s + a] - g->origin[a]) / h;
    double ar = area ? area[s] / (h * h) : (spacing * spacing) / (h * h);
    ps->area[s] = ar;
    ps->w[s] = alpha * ar;
    ps->wsum += ar;
  }
  if (!(ps->wsum > 0.0)) {
    /* all areas zero: fall back to uniform weights */
    for (size_t s = 0; s < n; ++s) {
      ps->area[s] = (spacing * spacing) / (h * h);
      ps->w[s] = alpha * ps->area[s];
    }
    ps->wsum = (double)n * ps->area[0];
  }
}

/* Multigrid level l: sizes, stencil offsets, domain and screening, and (l > 0)
 * its solution and right-hand side. */
static dacpo_status
ps_build_level(dacpo_poisson* ps, size_t l, size_t band, dacpo_err* err)
{
  mg_level* L = &ps->lv[l];
  for (int a = 0; a < 3; ++a)
    L->n[a] = ps->grid.dims[a] >> l;
  L->cells = L->n[0] * L->n[1] * L->n[2];
  L->c = (float)((size_t)1 << l);
  const ptrdiff_t sx = 1, sy = (ptrdiff_t)L->n[0], sz = (ptrdiff_t)(L->n[0] * L->n[1]);
  for (int o = 0; o < 27; ++o)
    L->off[o] = (ptrdiff_t)(o % 3 - 1) * sx + (ptrdiff_t)((o / 3) % 3 - 1) * sy +
                (ptrdiff_t)(o / 9 - 1) * sz;
  L->nb[0] = -sx, L->nb[1] = sx, L->nb[2] = -sy, L->nb[3] = sy, L->nb[4] = -sz,
  L->nb[5] = sz;
  DACPO_TRY(l == 0 ? build_domain0(ps, band, err) : build_domain_coarse(ps, l, err));
  DACPO_TRY(build_screening(ps, L, 1.0 / (double)((size_t)1 << l), err));
  if (l > 0) {
    L->x = (float*)ps_alloc(ps, L->cells, sizeof(float), 1);
    L->b = (float*)ps_alloc(ps, L->cells, sizeof(float), 1);
    if (!L->x || !L->b)
      return DACPO_OOM(err);
  }
  return DACPO_OK;
}

/* Every coordinate finite (their bounding box into lo/hi), every area finite
 * and >= 0. */
static dacpo_status
ps_check_samples(const double* xyz,
                 const double* area,
                 size_t n,
                 double lo[3],
                 double hi[3],
                 dacpo_err* err)
{
  for (int a = 0; a < 3; ++a) {
    lo[a] = HUGE_VAL;
    hi[a] = -HUGE_VAL;
  }
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      double v = xyz[3 * i + a];
      DACPO_CHECK(err,
                  isfinite(v),
                  DACPO_ERR_NONFINITE_INPUT,
                  "poisson: sample %zu has a non-finite coordinate",
                  i);
      if (v < lo[a])
        lo[a] = v;
      if (v > hi[a])
        hi[a] = v;
    }
  if (area)
    for (size_t i = 0; i < n; ++i)
      DACPO_CHECK(err,
                  isfinite(area[i]) && area[i] >= 0.0,
                  DACPO_ERR_INVALID_ARGUMENT,
                  "poisson: area of sample %zu is %g",
                  i,
                  area[i]);
  return DACPO_OK;
}

/* alpha in the PSR convention (relative to the box, Kazhdan & Hoppe 2013
 * Eq. 4) becomes alpha / (box side in cells) once lengths are in cells. */
static double
ps_cell_alpha(const dacpo_grid* g, double point_weight)
{
  size_t dmax = g->dims[0];
  for (int a = 1; a < 3; ++a)
    if (g->dims[a] > dmax)
      dmax = g->dims[a];
  return point_weight / (double)dmax;
}

/* The solver's vectors on the finest and the coarsest level, the coarsest
 * level's inverse diagonal, and chi = 1/2 (the first solve starts there). */
static dacpo_status
ps_alloc_solver(dacpo_poisson* ps, dacpo_err* err)
{
  const size_t cells = ps->lv[0].cells;
  ps->chi = (float*)ps_alloc(ps, cells, sizeof(float), 0);
  ps->r = (float*)ps_alloc(ps, cells, sizeof(float), 1);
  ps->z = (float*)ps_alloc(ps, cells, sizeof(float), 1);
  ps->p = (float*)ps_alloc(ps, cells, sizeof(float), 1);
  ps->q = (float*)ps_alloc(ps, cells, sizeof(float), 1);
  const mg_level* Cst = &ps->lv[ps->levels - 1];
  ps->cr = (float*)ps_alloc(ps, Cst->cells, sizeof(float), 1);
  ps->cp = (float*)ps_alloc(ps, Cst->cells, sizeof(float), 1);
  ps->cq = (float*)ps_alloc(ps, Cst->cells, sizeof(float), 1);
  ps->cz = (float*)ps_alloc(ps, Cst->cells, sizeof(float), 1);
  ps->cdiag = (float*)ps_alloc(ps, Cst->cells, sizeof(float), 1);
  if (!ps->chi || !ps->r || !ps->z || !ps->p || !ps->q || !ps->cr || !ps->cp ||
      !ps->cq || !ps->cz || !ps->cdiag)
    return DACPO_OOM(err);
  for (size_t i = 0; i < Cst->cells; ++i) {
    if (!Cst->flags[i])
      continue;
    float d = dacpo_mg_diag(Cst, i);
    ps->cdiag[i] = d > 0.0f ? 1.0f / d : 0.0f;
  }
  for (size_t i = 0; i < cells; ++i)
    ps->chi[i] = 0.5f;
  ps->iso = 0.5;
  return DACPO_OK;
}

dacpo_status
dacpo_poisson_create(const double* xyz,
                     const double* area,
                     size_t n,
                     double spacing,
                     const dacpo_poisson_params* params,
                     dacpo_poisson** out,
                     dacpo_err* err)
{
  DACPO_CHECK(err, out, DACPO_ERR_INVALID_ARGUMENT, "poisson: out is NULL");
  *out = NULL;
  DACPO_CHECK(err, xyz && params, DACPO_ERR_INVALID_ARGUMENT, "poisson: NULL argument");
  DACPO_CHECK(err, n > 0, DACPO_ERR_INVALID_ARGUMENT, "poisson: no samples");
  DACPO_CHECK(err,
              n <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "poisson: %zu samples exceed int32 indices",
              n);
  DACPO_TRY(ps_check_params(spacing, params, err));
  double lo[3], hi[3];
  DACPO_TRY(ps_check_samples(xyz, area, n, lo, hi, err));

  dacpo_poisson* ps = (dacpo_poisson*)calloc(1, sizeof(*ps));
  if (!ps)
    return DACPO_OOM(err);
  ps->bytes = sizeof(*ps);
  ps->n = n;
  ps->tolerance = params->tolerance;
  ps->max_cg = params->max_cg_iterations ? params->max_cg_iterations : 1;
  dacpo_status st = DACPO_OK;
  if (!choose_grid(lo, hi, spacing, params, &ps->grid, &ps->levels)) {
    st = dacpo_err_set(err,
                       DACPO_ERR_INVALID_ARGUMENT,
                       "poisson: no grid fits max_resolution %zu and max_cells %zu",
                       params->max_resolution,
                       params->max_cells);
    goto fail;
  }
  const double alpha = ps_cell_alpha(&ps->grid, params->point_weight);

  ps->u = (double*)ps_alloc(ps, 3 * n, sizeof(double), 0);
  ps->w = (double*)ps_alloc(ps, n, sizeof(double), 0);
  ps->area = (double*)ps_alloc(ps, n, sizeof(double), 0);
  ps->sc = (int32_t*)ps_alloc(ps, 8 * n, sizeof(int32_t), 0);
  ps->sw = (float*)ps_alloc(ps, 8 * n, sizeof(float), 0);
  if (!ps->u || !ps->w || !ps->area || !ps->sc || !ps->sw) {
    st = DACPO_OOM(err);
    goto fail;
  }
  ps_set_samples(ps, xyz, area, n, spacing, alpha);

  for (size_t l = 0; l < ps->levels; ++l)
    if ((st = ps_build_level(ps, l, params->band, err)) != DACPO_OK)
      goto fail;
  for (size_t s = 0; s < n; ++s)
    cell_stencil(ps->lv[0].n, ps->u + 3 * s, ps->sc + 8 * s, ps->sw + 8 * s);
  if ((st = ps_alloc_solver(ps, err)) != DACPO_OK)
    goto fail;
  *out = ps;
  return DACPO_OK;
fail:
  dacpo_poisson_free(ps);
  return st;
}

/* Right-hand side: -div V (V splatted on the faces) + alpha S 1/2. */
static void
build_rhs(dacpo_poisson* ps, const double* nrm, float* b)
{
  const mg_level* L = &ps->lv[0];
  const size_t n0 = L->n[0], n1 = L->n[1], n2 = L->n[2];
  for (size_t r = 0; r < L->nruns; ++r)
    memset(b + L->runs[r].base + L->runs[r].i0,
           0,
           (L->runs[r].i1 - L->runs[r].i0) * sizeof(float));
  const long lim[3] = {(long)n0, (long)n1, (long)n2};
  for (size_t s = 0; s < ps->n; ++s) {
    const double* u = ps->u + 3 * s;
    for (int a = 0; a < 3; ++a) {
      double v = nrm[3 * s + a] * ps->area[s];
      if (v == 0.0)
        continue;
      /* Faces normal to axis a sit at integer u[a] and at cell centres on
       * the other two axes; trilinear weights on that staggered grid. */
      long lo[3];
      double f[3];
      for (int e = 0; e < 3; ++e) {
        double t = e == a ? u[e] : u[e] - 0.5;
        double fl = floor(t);
        lo[e] = (long)fl;
        f[e] = t - fl;
      }
      const size_t stride = a == 0 ? 1 : (a == 1 ? n0 : n0 * n1);
      for (int c = 0; c < 8; ++c) {
        long id[3];
        double w = 1.0;
        for (int e = 0; e < 3; ++e) {
          int bit = (c >> e) & 1;
          id[e] = lo[e] + bit;
          w *= bit ? f[e] : 1.0 - f[e];
        }
        if (w == 0.0)
          continue;
        /* Faces inside the domain only: the domain's border carries no flux
         * (Neumann). */
        if (id[a] < 1 || id[a] >= lim[a])
          continue;
        for (int e = 0; e < 3; ++e)
          if (e != a) {
            if (id[e] < 0)
              id[e] = 0;
            if (id[e] >= lim[e])
              id[e] = lim[e] - 1;
          }
        size_t upper = (size_t)id[0] + n0 * ((size_t)id[1] + n1 * (size_t)id[2]);
        if (!L->flags[upper] || !L->flags[upper - stride])
          continue;
        float fv = (float)(w * v);
        b[upper] += fv;
        b[upper - stride] -= fv;
      }
    }
    const double half = 0.5 * ps->w[s];
    for (int c = 0; c < 8; ++c)
      b[ps->sc[8 * s + c]] += (float)(half * ps->sw[8 * s + c]);
  }
}

static double
iso_of(const dacpo_poisson* ps)
{
  double acc = 0.0;
  for (size_t s = 0; s < ps->n; ++s) {
    double v = 0.0;
    for (int c = 0; c < 8; ++c)
      v += (double)ps->sw[8 * s + c] * (double)ps->chi[ps->sc[8 * s + c]];
    acc += ps->area[s] * v;
  }
  return acc / ps->wsum;
}

dacpo_status
dacpo_poisson_solve(dacpo_poisson* ps,
                    const double* nrm,
                    dacpo_poisson_info* info,
                    dacpo_err* err)
{
  DACPO_CHECK(
      err, ps && nrm, DACPO_ERR_INVALID_ARGUMENT, "poisson_solve: NULL argument");
  mg_level* L = &ps->lv[0];
  float *x = ps->chi, *r = ps->r, *z = ps->z, *p = ps->p, *q = ps->q;
  build_rhs(ps, nrm, r);
  double bb = dacpo_mg_dot(L, r, r);
  dacpo_mg_apply(L, x, q);
  dacpo_mg_axpy(L, -1.0f, q, r);
  double rr = dacpo_mg_dot(L, r, r);
  const double stop = ps->tolerance * ps->tolerance * bb;
  size_t it = 0;
  if (rr > stop) {
    dacpo_mg_vcycle(ps, 0, z, r);
    memcpy(p, z, L->cells * sizeof(float));
    double rz = dacpo_mg_dot(L, r, z);
    for (it = 1; it <= ps->max_cg; ++it) {
      dacpo_mg_apply(L, p, q);
      double pq = dacpo_mg_dot(L, p, q);
      if (!(pq > 0.0) || !(rz > 0.0))
        break;
      float alpha = (float)(rz / pq);
      dacpo_mg_axpy(L, alpha, p, x);
      dacpo_mg_axpy(L, -alpha, q, r);
      rr = dacpo_mg_dot(L, r, r);
      if (rr <= stop || it == ps->max_cg)
        break;
      dacpo_mg_vcycle(ps, 0, z, r);
      /* Polak-Ribiere beta: (z_new . (r_new - r_old)) / (z_old . r_old), with
       * r_new - r_old = -alpha q. */
      double zr = dacpo_mg_dot(L, z, r);
      double zq = dacpo_mg_dot(L, z, q);
      float beta = (float)((zr - (double)alpha * zq) / rz);
      if (beta < 0.0f)
        beta = 0.0f;
      rz = zr;
      dacpo_mg_xpby(L, z, beta, p);
    }
  }
  ps->iso = iso_of(ps);
  if (info) {
    info->iterations = it;
    info->residual = bb > 0.0 ? sqrt(rr / bb) : 0.0;
    info->iso_value = ps->iso;
  }
  return DACPO_OK;
}

const dacpo_grid*
dacpo_poisson_grid(const dacpo_poisson* ps)
{
  return ps ? &ps->grid : NULL;
}

const float*
dacpo_poisson_values(const dacpo_poisson* ps)
{
  return ps ? ps->chi : NULL;
}

const uint8_t*
dacpo_poisson_domain(const dacpo_poisson* ps)
{
  return ps ? ps->lv[0].flags : NULL;
}

size_t
dacpo_poisson_domain_cells(const dacpo_poisson* ps)
{
  return ps ? ps->lv[0].active : 0;
}

double
dacpo_poisson_evaluate(const dacpo_poisson* ps, const double p[3])
{
  if (!ps || !p)
    return 0.0;
  double u[3];
  for (int a = 0; a < 3; ++a)
    u[a] = (p[a] - ps->grid.origin[a]) / ps->grid.cell;
  int32_t cell[8];
  float wt[8];
  cell_stencil(ps->lv[0].n, u, cell, wt);
  double v = 0.0, ws = 0.0;
  for (int c = 0; c < 8; ++c)
    if (ps->lv[0].flags[cell[c]]) {
      v += (double)wt[c] * (double)ps->chi[cell[c]];
      ws += (double)wt[c];
    }
  return ws > 0.0 ? v / ws : ps->iso;
}

size_t
dacpo_poisson_bytes(const dacpo_poisson* ps)
{
  return ps ? ps->bytes : 0;
}
