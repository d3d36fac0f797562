/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 3a: the screened Poisson solver's state (dacpo_poisson.c) and the
 * multigrid kernels it calls (dacpo_poisson_multigrid.c). Private to them. */
#ifndef DACPO_POISSON_INTERNAL_H
#define DACPO_POISSON_INTERNAL_H

#include "dacpo_poisson.h"

#include <stddef.h>
#include <stdint.h>

#define DACPO_POISSON_MAX_LEVELS 12
/* The coarsest level has at most this many cells per axis. */
#define DACPO_POISSON_COARSEST 8

/* Cell flags: bit d (0..5 = -x, +x, -y, +y, -z, +z) set when that neighbour is
 * in the domain; IN set for every domain cell; 0 outside the domain. */
enum { F_IN = 0x40, F_FULL = 0x7F };

typedef struct mg_run {
  size_t base; /* index of cell (0, j, k) */
  uint32_t i0; /* cells base + i0 .. base + i1 - 1 */
  uint32_t i1;
} mg_run;

typedef struct mg_level {
  size_t n[3];
  size_t cells;
  size_t active;
  float c;        /* Laplacian face coefficient: cell edge in finest-cell units */
  float* x;       /* levels >= 1: correction; level 0 uses the CG arrays */
  float* b;       /* levels >= 1: restricted residual */
  uint8_t* flags; /* per cell, see F_* */
  mg_run* runs;
  size_t nruns;
  int32_t* srow; /* screening row of each cell, or -1 */
  float* sval;   /* 27 coefficients per screening row, offset (dx,dy,dz) at
                    (dx+1) + 3 (dy+1) + 9 (dz+1) */
  size_t rows;
  ptrdiff_t off[27]; /* index offset of each screening coefficient */
  ptrdiff_t nb[6];   /* index offset of each face neighbour */
} mg_level;

struct dacpo_poisson {
  dacpo_grid grid;
  size_t n;
  double* u;    /* 3n sample positions in finest-cell units from the origin */
  double* w;    /* n screening weights alpha' * area (cell units) */
  double* area; /* n areas in cell units (splat weights) */
  int32_t* sc;  /* 8n cell-centre interpolation cells on level 0 */
  float* sw;    /* 8n weights */
  double wsum;
  size_t levels;
  mg_level lv[DACPO_POISSON_MAX_LEVELS];
  /* CG on level 0 (chi lives in chi) */
  float* chi;
  float* r;
  float* z;
  float* p;
  float* q;
  /* Jacobi-CG on the coarsest level */
  float* cr;
  float* cp;
  float* cq;
  float* cz;
  float* cdiag;
  double iso;
  double tolerance;
  size_t max_cg;
  size_t bytes;
};

/* y = A x on level L (its domain cells). */
void
dacpo_mg_apply(const mg_level* L, const float* x, float* y);
/* The diagonal of A at cell idx. */
float
dacpo_mg_diag(const mg_level* L, size_t idx);
/* Dot product over L's domain cells (double accumulation). */
double
dacpo_mg_dot(const mg_level* L, const float* a, const float* b);
/* y += alpha x over L's domain cells. */
void
dacpo_mg_axpy(const mg_level* L, float alpha, const float* x, float* y);
/* p = z + beta p over L's domain cells. */
void
dacpo_mg_xpby(const mg_level* L, const float* z, float beta, float* p);
/* One V-cycle from level l: x approximately solves A x = b there. */
void
dacpo_mg_vcycle(dacpo_poisson* ps, size_t l, float* x, const float* b);

#endif
