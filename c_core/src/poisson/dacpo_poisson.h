/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 3a: screened Poisson indicator with Neumann boundary on a block's box
 * (paper §4.3, Kazhdan & Hoppe 2013). Set up once per block
 * (grid, narrow-band domain, multigrid hierarchy, screening stencils), then
 * solved many times from different normals with a warm start: the points never
 * move in iPSR. */
#ifndef DACPO_POISSON_H
#define DACPO_POISSON_H

#include "dacpo_internal.h"

/* A regular grid of cubic cells; values live at cell centres
 * origin + (i + 1/2, j + 1/2, k + 1/2) * cell, stored x fastest:
 * index = i + dims[0] * (j + dims[1] * k). */
typedef struct dacpo_grid {
  size_t dims[3];
  double origin[3];
  double cell;
} dacpo_grid;

typedef struct dacpo_poisson_params {
  double cell_per_spacing; /* cell edge / sample spacing (1.0) */
  size_t max_resolution;   /* cap on cells per axis (128) */
  size_t max_cells;        /* cap on all cells, bounds memory (1.5e6, ~27 B each) */
  double padding;          /* band 0 only: the box grows by this share of its longest
                              side on every side (0.1); with a band, by band + 2 cells */
  double point_weight; /* screening alpha, PSR convention: relative to the box (16) */
  double tolerance;    /* stop when |r| <= tolerance * |b| (1e-3) */
  size_t max_cg_iterations; /* multigrid-preconditioned CG steps per solve (30) */
  size_t band;              /* domain: cells within this many cells of a sample's
                               stencil (Chebyshev; at least 2); 0 = the whole box (2) */
} dacpo_poisson_params;

void
dacpo_poisson_params_default(dacpo_poisson_params* p);

typedef struct dacpo_poisson dacpo_poisson;

/* Builds the solver for n samples (3n doubles; copied as needed, not kept).
 * area: per-sample surface area (n doubles, may be NULL: every sample gets
 * spacing^2); it weights both the normal splat and the screening. spacing > 0
 * is the typical sample distance; the cell is cell_per_spacing * spacing unless
 * a cap enlarges it.
 * Errors: INVALID_ARGUMENT (n == 0, bad params or areas), NONFINITE_INPUT (a
 * non-finite coordinate, with its index), OUT_OF_MEMORY. One solver object is
 * used by one thread at a time; separate objects are independent. */
dacpo_status
dacpo_poisson_create(const double* xyz,
                     const double* area,
                     size_t n,
                     double spacing,
                     const dacpo_poisson_params* params,
                     dacpo_poisson** out,
                     dacpo_err* err);

void
dacpo_poisson_free(dacpo_poisson* ps);

typedef struct dacpo_poisson_info {
  size_t iterations; /* CG steps (one V-cycle each) */
  double residual;   /* final |r| / |b| */
  double iso_value;  /* area-weighted mean of chi at the samples */
} dacpo_poisson_info;

/* Solves (L + alpha S) chi = -div V + alpha S 1/2 for the normals nrm (3n,
 * same order as at create; need not be unit), starting from the previous
 * solution (the first solve starts from chi = 1/2). chi grows along the
 * normals: high in front of the surface, low behind it. info may be NULL.
 * Never fails on finite normals; returns INVALID_ARGUMENT for NULL args. */
dacpo_status
dacpo_poisson_solve(dacpo_poisson* ps,
                    const double* nrm,
                    dacpo_poisson_info* info,
                    dacpo_err* err);

/* The grid and chi at its cell centres (valid until the next solve/free).
 * chi is meaningful on the domain only: domain[i] != 0 marks its cells. */
const dacpo_grid*
dacpo_poisson_grid(const dacpo_poisson* ps);
const float*
dacpo_poisson_values(const dacpo_poisson* ps);
const uint8_t*
dacpo_poisson_domain(const dacpo_poisson* ps);
size_t
dacpo_poisson_domain_cells(const dacpo_poisson* ps);

/* chi at any point (trilinear between the domain's cell centres, clamped to
 * the box; the iso-value where no domain cell is near). */
double
dacpo_poisson_evaluate(const dacpo_poisson* ps, const double p[3]);

/* Bytes currently allocated by the solver. */
size_t
dacpo_poisson_bytes(const dacpo_poisson* ps);

#endif /* DACPO_POISSON_H */
