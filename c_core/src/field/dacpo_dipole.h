/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 2: dipole-field randomized greedy orientation of one block (paper §4.2,
 * Eq. 1-4). */
#ifndef DACPO_DIPOLE_H
#define DACPO_DIPOLE_H

#include "dacpo_internal.h"

typedef struct dacpo_dipole_params {
  double c;         /* Eq. 1 constant (4 clean, 2 noisy) */
  size_t orders;    /* M randomized BFS orders */
  size_t neighbors; /* K nearest placed points summed per decision */
  size_t graph_k;   /* k of the BFS graph */
  int final_sweep;  /* re-decision sweeps with all neighbours placed (until
                       none changes, at most this many; 0 = none) */
  size_t restarts;  /* independent runs of the M orders (0 or 1 = one run) */
  uint64_t seed;
  uint64_t stream;   /* e.g. the block id: independent of thread count */
  double two_sheet;  /* 0 = off; else pairs on two sheets of one thin part
                        (offsets beyond two_sheet x local noise, see
                        dacpo_params.dipole_two_sheet) must face opposite ways */
  double layers;     /* 0 = off; else, in a block seen from one side, parallel
                        pairs offset by more than layers x local spacing get
                        c = 1 (dacpo_params.dipole_layers) */
  double c_thin;     /* 0 = off; else, in a block with thin two-sided parts
                        (two_sheet > 0), pairs offset beyond two_sheet x local
                        noise get this c (dacpo_params.dipole_c_thin) */
  double sides;      /* 0 = off; else weight of the thin-part side cue
                        (dacpo_sheet_side.h; dacpo_params.dipole_sides) */
  int sides_everywhere; /* 1: every block gets the side cue (a scene seen from
                           many places); 0: only blocks where >= 5 % of the
                           points show it (a single depth view, whose noise
                           fires it on up to 3.5 % of a block) */
  size_t sides_fit_k;   /* neighbours of the cue's surface fit, <=
                           DACPO_SIDE_MAX_NEIGHBORS (0: 24) */
  uint8_t* thin_out; /* optional output (n entries, may be NULL): 1 where the
                        side cue fired, i.e. the point lies on a part thinner
                        than the block's Poisson grid resolves (stage 3 keeps
                        its stage-2 normal) */
  int8_t* cue_out;   /* optional output (n entries, may be NULL): +1 where the
                        side cue fired and agrees with the returned sign, -1
                        where it disagrees, 0 elsewhere */
  size_t* restarts_out; /* optional output (may be NULL): restarts run (fewer
                           than `restarts` when the first ones agree) */
} dacpo_dipole_params;

/* The two-sheet test's local noise scale of point p (unit axis a): the 25th
 * percentile of |offset| from its tangent plane of the first
 * min(m, DACPO_TWO_SHEET_NEAREST) points of row (indices into xyz; negative
 * entries skipped); 0 when none. Low enough that a second sheet (up to half
 * the neighbours) does not count as noise. */
double
dacpo_two_sheet_noise(const double p[3],
                      const double a[3],
                      const double* xyz,
                      const int32_t* row,
                      size_t m);

/* Stage 2's two-sheet pair test: 1 if (p, axis a) and (q, axis b) lie on two
 * sheets of one thin part (or two copies of one surface): axes within ~37
 * degrees, each point off the other's tangent plane by more than
 * max(factor x noise, 0.5 x spacing) plus the bend of one curved sheet, and by
 * less than 2 x local. noise, local: the larger local noise scale and local
 * spacing of the two points; spacing: the block's (or scene's) typical
 * nearest-neighbour distance. */
int
dacpo_two_sheet_pair(const double p[3],
                     const double a[3],
                     const double q[3],
                     const double b[3],
                     double noise,
                     double local,
                     double factor,
                     double spacing);
/* e((p,n),(p',n')) = F_{p,n}(p') . n' with F of Eq. 1. Exposed for tests and for
 * the dipole-boundary edge weight. Returns 0 for |r| below 1e-12 relative. */
double
dacpo_dipole_energy(const double p[3],
                    const double n[3],
                    const double q[3],
                    const double m[3],
                    double c);

/* Orients n points (xyz, nrm: 3n, nrm unit axes) of one block: sign_out[i] is
 * +1 or -1, the block's normals being sign_out[i] * nrm[i]. The overall sign is
 * arbitrary (the global stage decides it). Builds its own local kd-tree. */
dacpo_status
dacpo_dipole_orient(const double* xyz,
                    const double* nrm,
                    size_t n,
                    const dacpo_dipole_params* params,
                    int8_t* sign_out,
                    dacpo_err* err);

/* The same, and confidence[i] in [0, 1] (NULL: not computed): the share of
 * restarts that agree with point i's sign times the margin of its last
 * decision (|sum of the neighbours' field| / sum of its magnitudes). */
dacpo_status
dacpo_dipole_orient_confidence(const double* xyz,
                               const double* nrm,
                               size_t n,
                               const dacpo_dipole_params* params,
                               int8_t* sign_out,
                               float* confidence,
                               dacpo_err* err);

#endif
