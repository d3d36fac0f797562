/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 4b: visible connected regions between two adjacent blocks' meshes
 * (paper §5.1). */
#ifndef DACPO_VCR_H
#define DACPO_VCR_H

#include "dacpo_internal.h"

/* Paper variants kept only for comparison runs (the VCR tests and bench_vcr):
 * measured no better than the defaults, so neither dacpo_params nor the tools
 * reach them. Both 0 by default. */
typedef struct dacpo_vcr_experiment {
  int drop_partial; /* 1: remove the pixels of triangles that are only partly
                       visible (paper Fig. "VCR" (b, e)) */
  int eta_all;      /* 0: eta = largest depth span of the triangles that own at
                       least one pixel; 1: of all triangles (paper's formula) */
} dacpo_vcr_experiment;

typedef struct dacpo_vcr_params {
  size_t image_size;   /* 400 */
  size_t num_views;    /* 12 (dodecahedron face centres) */
  int perspective;     /* 0 orthographic, 1 perspective */
  int boundary_factor; /* 1: I = C_B*C1*C2 (paper); 0: I = C1*C2 */
  /* Seam closing (defaults from dacpo_vcr_params_default): */
  size_t gap_fill;       /* 2: empty pixels within this many 4-steps of a drawn pixel
                            take the nearest neighbour's depth and triangle, so a seam
                            of up to 2*gap_fill pixels between the two meshes still
                            joins them; 0 = off */
  double gap_fill_edges; /* 0.75: per view, the seam closing reaches at least
                            this many median triangle edges (converted to pixels,
                            at most DACPO_VCR_GAP_MAX): block meshes cut face by
                            face can leave seams about one face wide (the stage-3
                            meshes of the 15 scans did not need it); 0 = off */
  dacpo_vcr_experiment experiment; /* paper variants, off (above) */
} dacpo_vcr_params;

/* Upper bound (pixels) of the seam closing chosen by gap_fill_edges. */
#define DACPO_VCR_GAP_MAX 8

void
dacpo_vcr_params_default(dacpo_vcr_params* p);

/* alpha: view-alignment evidence with both meshes as they are; alpha_bar: the
 * same with mesh b's facing inverted (same z-buffer, labelled twice).
 * (Implementation notes: params NULL = defaults. alpha sums I = C_B*C1*C2 with
 * C1, C2 divided by image_size^2 and C_B by image_size, so flipping b swaps
 * alpha and alpha_bar exactly. Empty meshes: both 0, DACPO_OK. Errors:
 * DACPO_ERR_INVALID_ARGUMENT (bad parameter, vertex index out of range,
 * non-finite vertex), DACPO_ERR_OUT_OF_MEMORY. Thread-safe: scratch is per call.) */
typedef struct dacpo_vcr_trace dacpo_vcr_trace; /* optional diagnostics, below */
dacpo_status
dacpo_vcr_edge(const dacpo_mesh* a,
               const dacpo_mesh* b,
               const dacpo_vcr_params* params,
               double* alpha,
               double* alpha_bar,
               dacpo_vcr_trace* trace,
               dacpo_err* err);

/* Unit view directions used for num_views views (the camera looks along them):
 * num_views <= 12: the first num_views of the 12 icosahedron vertex directions
 * (= dodecahedron face centres), ordered so that the first 6 are one of each
 * antipodal pair and the last 6 their opposites; num_views > 12: a Fibonacci
 * sphere. dirs holds 3 * num_views doubles. */
void
dacpo_vcr_view_directions(size_t num_views, double* dirs);

/* What one view contributed (diagnostics). */
typedef struct dacpo_vcr_view_stats {
  double direction[3]; /* the camera looks along it */
  double eta;          /* depth threshold of this view (0 if nothing drawn) */
  size_t pixels_a;     /* pixels won by mesh a / b after the z-test (and gap fill) */
  size_t pixels_b;
  size_t cross_same; /* depth-continuous 4-neighbour pixel pairs across the two */
  size_t cross_diff; /* meshes whose facing agrees / differs (as given) */
  size_t regions;    /* sub-regions holding both meshes: as given / b inverted */
  size_t regions_bar;
  double alpha; /* this view's share of alpha / alpha_bar */
  double alpha_bar;
  size_t gap_pixels; /* seam-closing radius used in this view */
} dacpo_vcr_view_stats;

/* Label codes written to a dacpo_vcr_trace's images. */
#define DACPO_VCR_PIXEL_EMPTY 0
#define DACPO_VCR_PIXEL_A_FRONT 1 /* mesh a, face normal towards the camera */
#define DACPO_VCR_PIXEL_A_BACK 2
#define DACPO_VCR_PIXEL_B_FRONT 3
#define DACPO_VCR_PIXEL_B_BACK 4
#define DACPO_VCR_PIXEL_BOUNDARY                                                       \
  8 /* or-ed in: has a depth-continuous                                                \
       4-neighbour of the other mesh */

/* What dacpo_vcr_edge can report besides alpha / alpha_bar (trace NULL: nothing):
 * per-view statistics (views: NULL or params->num_views entries) and label
 * images (images: NULL or num_views * image_size * image_size bytes, row-major,
 * codes above; views that draw nothing stay 0). An orthographic view drawn
 * with its opposite (dacpo_vcr.c) is stored as the opposite view's pixel grid
 * sees it: mirrored against a camera of its own. */
struct dacpo_vcr_trace {
  dacpo_vcr_view_stats* views;
  uint8_t* images;
};

#endif
