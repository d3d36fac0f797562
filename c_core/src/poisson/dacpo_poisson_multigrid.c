/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 3a, the solver's kernels (dacpo_poisson.c builds the levels and runs
 * the CG): the level operator (7-point Laplacian of the domain's cells plus the
 * screening rows), Gauss-Seidel sweeps, trilinear prolongation with its
 * transpose as restriction, the Jacobi-CG coarsest solve, and the symmetric
 * V-cycle that preconditions CG. Every kernel walks a level's domain as runs
 * of cells along x. */
#include "dacpo_poisson_internal.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Level operators. Cells with all six neighbours in the domain (flag F_FULL,
 * never on the box's border) take a branch-free path; screening rows of such
 * cells may read all 27 neighbours, the others only their non-zero entries. */

/* (A x)_idx */
static inline float
cell_apply(const mg_level* L, const float* x, size_t idx)
{
  const uint8_t f = L->flags[idx];
  const ptrdiff_t* nb = L->nb;
  const float xc = x[idx];
  float acc;
  if (f == F_FULL)
    acc = 6.0f * xc - (x[idx + nb[0]] + x[idx + nb[1]] + x[idx + nb[2]] +
                       x[idx + nb[3]] + x[idx + nb[4]] + x[idx + nb[5]]);
  else {
    acc = 0.0f;
    for (int d = 0; d < 6; ++d)
      if (f & (1 << d))
        acc += xc - x[(ptrdiff_t)idx + nb[d]];
  }
  acc *= L->c;
  const int32_t row = L->srow[idx];
  if (row >= 0) {
    const float* sv = L->sval + 27 * (size_t)row;
    for (int o = 0; o < 27; ++o)
      if (f == F_FULL || sv[o] != 0.0f)
        acc += sv[o] * x[(ptrdiff_t)idx + L->off[o]];
  }
  return acc;
}

/* Gauss-Seidel update of one cell. */
static inline void
cell_relax(const mg_level* L, float* x, const float* b, size_t idx)
{
  const uint8_t f = L->flags[idx];
  const ptrdiff_t* nb = L->nb;
  float sum;
  int cnt;
  if (f == F_FULL) {
    sum = x[idx + nb[0]] + x[idx + nb[1]] + x[idx + nb[2]] + x[idx + nb[3]] +
          x[idx + nb[4]] + x[idx + nb[5]];
    cnt = 6;
  }
  else {
    sum = 0.0f;
    cnt = 0;
    for (int d = 0; d < 6; ++d)
      if (f & (1 << d))
        sum += x[(ptrdiff_t)idx + nb[d]], ++cnt;
  }
  float s = b[idx] + L->c * sum;
  float d = L->c * (float)cnt;
  const int32_t row = L->srow[idx];
  if (row >= 0) {
    const float* sv = L->sval + 27 * (size_t)row;
    d += sv[13];
    for (int o = 0; o < 27; ++o)
      if (o != 13 && (f == F_FULL || sv[o] != 0.0f))
        s -= sv[o] * x[(ptrdiff_t)idx + L->off[o]];
  }
  /* d > 0: every domain cell has a neighbour or a screening weight */
  x[idx] = d > 0.0f ? s / d : 0.0f;
}

void
dacpo_mg_apply(const mg_level* L, const float* x, float* y)
{
  for (size_t r = 0; r < L->nruns; ++r) {
    const mg_run* run = &L->runs[r];
    for (size_t i = run->base + run->i0; i < run->base + run->i1; ++i)
      y[i] = cell_apply(L, x, i);
  }
}

static void
gauss_seidel(const mg_level* L, float* x, const float* b, int backward)
{
  if (!backward) {
    for (size_t r = 0; r < L->nruns; ++r) {
      const mg_run* run = &L->runs[r];
      for (size_t i = run->base + run->i0; i < run->base + run->i1; ++i)
        cell_relax(L, x, b, i);
    }
  }
  else {
    for (size_t r = L->nruns; r-- > 0;) {
      const mg_run* run = &L->runs[r];
      for (size_t i = run->base + run->i1; i-- > run->base + run->i0;)
        cell_relax(L, x, b, i);
    }
  }
}

float
dacpo_mg_diag(const mg_level* L, size_t idx)
{
  const uint8_t f = L->flags[idx];
  int cnt = 0;
  for (int d = 0; d < 6; ++d)
    cnt += (f >> d) & 1;
  float d = L->c * (float)cnt;
  if (L->srow[idx] >= 0)
    d += L->sval[27 * (size_t)L->srow[idx] + 13];
  return d;
}

/* Trilinear cell-centred prolongation: fine cell (i, j, k) takes 27/64 of its
 * parent, 9/64 of each face-adjacent coarse cell on its side, and so on. A
 * coarse cell outside the box or the coarse domain is replaced by the parent
 * (Neumann reflection). Restriction is the transpose. */
typedef struct prolong_row {
  size_t row[4]; /* coarse row bases: (y near|far) x (z near|far) */
} prolong_row;

static inline size_t
far_index(size_t i, size_t nc)
{
  size_t I = i >> 1;
  if (i & 1)
    return I + 1 < nc ? I + 1 : I;
  return I > 0 ? I - 1 : I;
}

static inline void
prolong_row_of(const mg_level* F, const mg_level* C, size_t base, prolong_row* pr)
{
  const size_t j = (base / F->n[0]) % F->n[1], k = base / (F->n[0] * F->n[1]);
  const size_t jn = j >> 1, jf = far_index(j, C->n[1]);
  const size_t kn = k >> 1, kf = far_index(k, C->n[2]);
  const size_t cx = C->n[0], cxy = C->n[0] * C->n[1];
  pr->row[0] = cx * jn + cxy * kn;
  pr->row[1] = cx * jf + cxy * kn;
  pr->row[2] = cx * jn + cxy * kf;
  pr->row[3] = cx * jf + cxy * kf;
}

/* The 8 coarse cells of fine cell i of a row; weights are kCornerW. */
static const float kCornerW[8] = {27.0f / 64,
                                  9.0f / 64,
                                  9.0f / 64,
                                  3.0f / 64,
                                  9.0f / 64,
                                  3.0f / 64,
                                  3.0f / 64,
                                  1.0f / 64};

static inline void
coarse_corners(const mg_level* C, const prolong_row* pr, size_t i, size_t ci[8])
{
  const size_t in = i >> 1, ifr = far_index(i, C->n[0]);
  const size_t parent = pr->row[0] + in;
  /* corner c: bit 0 x far, bit 1 y far, bit 2 z far */
  ci[0] = parent;
  ci[1] = pr->row[0] + ifr;
  ci[2] = pr->row[1] + in;
  ci[3] = pr->row[1] + ifr;
  ci[4] = pr->row[2] + in;
  ci[5] = pr->row[2] + ifr;
  ci[6] = pr->row[3] + in;
  ci[7] = pr->row[3] + ifr;
  for (int c = 1; c < 8; ++c)
    if (!C->flags[ci[c]])
      ci[c] = parent;
}

/* fine += P coarse */
static void
prolong_add(const mg_level* F, const mg_level* C, const float* xc, float* xf)
{
  size_t ci[8];
  prolong_row pr;
  for (size_t r = 0; r < F->nruns; ++r) {
    const mg_run* run = &F->runs[r];
    prolong_row_of(F, C, run->base, &pr);
    for (size_t i = run->i0; i < run->i1; ++i) {
      coarse_corners(C, &pr, i, ci);
      float v = 0.0f;
      for (int c = 0; c < 8; ++c)
        v += kCornerW[c] * xc[ci[c]];
      xf[run->base + i] += v;
    }
  }
}

/* coarse b = P^T (b - A x) on the fine level, fused so no fine residual array
 * is needed. */
static void
residual_restrict(
    const mg_level* F, const mg_level* C, const float* x, const float* b, float* bc)
{
  size_t ci[8];
  prolong_row pr;
  memset(bc, 0, C->cells * sizeof(float));
  for (size_t r = 0; r < F->nruns; ++r) {
    const mg_run* run = &F->runs[r];
    prolong_row_of(F, C, run->base, &pr);
    for (size_t i = run->i0; i < run->i1; ++i) {
      const size_t idx = run->base + i;
      const float res = b[idx] - cell_apply(F, x, idx);
      coarse_corners(C, &pr, i, ci);
      for (int c = 0; c < 8; ++c)
        bc[ci[c]] += kCornerW[c] * res;
    }
  }
}

double
dacpo_mg_dot(const mg_level* L, const float* a, const float* b)
{
  double s = 0.0;
  for (size_t r = 0; r < L->nruns; ++r) {
    const mg_run* run = &L->runs[r];
    float part = 0.0f;
    for (size_t i = run->base + run->i0; i < run->base + run->i1; ++i)
      part += a[i] * b[i];
    s += (double)part;
  }
  return s;
}

/* y += alpha x, on the domain */
void
dacpo_mg_axpy(const mg_level* L, float alpha, const float* x, float* y)
{
  for (size_t r = 0; r < L->nruns; ++r) {
    const mg_run* run = &L->runs[r];
    for (size_t i = run->base + run->i0; i < run->base + run->i1; ++i)
      y[i] += alpha * x[i];
  }
}

/* p = z + beta p, on the domain */
void
dacpo_mg_xpby(const mg_level* L, const float* z, float beta, float* p)
{
  for (size_t r = 0; r < L->nruns; ++r) {
    const mg_run* run = &L->runs[r];
    for (size_t i = run->base + run->i0; i < run->base + run->i1; ++i)
      p[i] = z[i] + beta * p[i];
  }
}

/* Jacobi-preconditioned CG on the coarsest level, from x = 0. */
static void
coarse_solve(dacpo_poisson* ps, const mg_level* L, float* x, const float* b)
{
  const size_t n = L->cells;
  float *r = ps->cr, *p = ps->cp, *q = ps->cq, *z = ps->cz;
  memset(x, 0, n * sizeof(float));
  memcpy(r, b, n * sizeof(float));
  double bb = dacpo_mg_dot(L, b, b);
  if (bb <= 0.0)
    return;
  for (size_t i = 0; i < n; ++i)
    z[i] = r[i] * ps->cdiag[i];
  memcpy(p, z, n * sizeof(float));
  double rz = dacpo_mg_dot(L, r, z);
  const size_t maxit = 2 * L->active + 50;
  for (size_t it = 0; it < maxit; ++it) {
    dacpo_mg_apply(L, p, q);
    double pq = dacpo_mg_dot(L, p, q);
    if (!(pq > 0.0))
      break;
    float alpha = (float)(rz / pq);
    dacpo_mg_axpy(L, alpha, p, x);
    dacpo_mg_axpy(L, -alpha, q, r);
    if (dacpo_mg_dot(L, r, r) <= 1e-10 * bb)
      break;
    for (size_t i = 0; i < n; ++i)
      z[i] = r[i] * ps->cdiag[i];
    double rz2 = dacpo_mg_dot(L, r, z);
    float beta = (float)(rz2 / rz);
    rz = rz2;
    dacpo_mg_xpby(L, z, beta, p);
  }
}

/* One V-cycle from x = 0 on level l: x ~ A_l^{-1} b. */
void
dacpo_mg_vcycle(dacpo_poisson* ps, size_t l, float* x, const float* b)
{
  mg_level* L = &ps->lv[l];
  if (l + 1 == ps->levels) {
    coarse_solve(ps, L, x, b);
    return;
  }
  mg_level* C = &ps->lv[l + 1];
  for (size_t r = 0; r < L->nruns; ++r)
    memset(x + L->runs[r].base + L->runs[r].i0,
           0,
           (L->runs[r].i1 - L->runs[r].i0) * sizeof(float));
  gauss_seidel(L, x, b, 0);
  gauss_seidel(L, x, b, 0);
  residual_restrict(L, C, x, b, C->b);
  dacpo_mg_vcycle(ps, l + 1, C->x, C->b);
  prolong_add(L, C, C->x, x);
  gauss_seidel(L, x, b, 1);
  gauss_seidel(L, x, b, 1);
}
