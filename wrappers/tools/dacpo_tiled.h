/* SPDX-License-Identifier: BSD-3-Clause */
/* Out-of-core orientation on one machine (pcl_dacpo_orient -memory): a
 * binary PLY is cut into spatial tiles (dacpo_advanced.h, "Tiles"), streamed
 * from disk into one temporary file per tile, oriented one tile at a time by
 * dacpo_orient(), joined, and written in input order; at no time does the
 * process hold more than one tile (own points + halo) and a sample. */
#ifndef DACPO_TILED_H
#define DACPO_TILED_H

#include <dacpo/dacpo_advanced.h>

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Peak bytes per point of one dacpo_orient() run with estimated normals
 * (measured: 500K-point room 361 MB, 722 bytes per point with the process;
 * rounded up) and the process's own share; the budget gives the tile size. */
#define DACPO_TILED_BYTES_PER_POINT 800.0
#define DACPO_TILED_BASE_BYTES (96.0 * 1024.0 * 1024.0)
/* Sample for the plan: every s-th point, s = ceil(n / this). */
#define DACPO_TILED_SAMPLE 200000

typedef struct dacpo_tiled_options {
  const char* input;   /* binary PLY */
  const char* output;  /* .ply: x y z nx ny nz (float), input order */
  const char* tmp_dir; /* tile files; NULL: beside the output */
  uint64_t max_points; /* own + halo points of one tile */
  double halo;         /* 0: automatic (dacpo_tile_plan_create) */
  dacpo_params params; /* estimate_normals is set here */
} dacpo_tiled_options;

typedef struct dacpo_tiled_report {
  uint64_t points;       /* input points */
  size_t tiles;          /* tiles in the plan */
  double halo;           /* halo width used */
  uint64_t halo_points;  /* points read twice or more (sum over tiles) */
  uint64_t largest_tile; /* own + halo points of the largest tile */
  size_t flipped_tiles;  /* tiles turned over by the join */
  double seconds[5];     /* sample + plan, route, tiles, join, flip + write */
  size_t blocks;         /* blocks over all tiles */
} dacpo_tiled_report;

/* The output's PLY header (x y z nx ny nz floats, n vertices); its length. */
int
dacpo_tiled_header(char* buf, size_t len, size_t tiles, uint64_t n);

/* count rows of xyz_bytes (dacpo_ply_rows_read_raw) become rows of xyz_bytes
 * + 12, the 3 floats at nrm + stride * i appended to row i, in place (rows
 * holds count x (xyz_bytes + 12) bytes). */
void
dacpo_tiled_append_normals(unsigned char* rows,
                           size_t xyz_bytes,
                           const float* nrm,
                           size_t stride,
                           size_t count);

struct dacpo_ply_rows;
/* The same with x y z of the input's types (rows; NULL: float), for outputs
 * that keep the input's coordinates bit for bit. */
int
dacpo_tiled_header_typed(char* buf,
                         size_t len,
                         size_t tiles,
                         uint64_t n,
                         const struct dacpo_ply_rows* rows);

/* The plan's sample: points whose input index is a multiple of this. */
uint64_t
dacpo_tiled_sample_stride(uint64_t n);

/* Record of the output: 3 float xyz, 3 float normal. */
#define DACPO_TILED_OUT_BYTES 24

/* weak_edge_fraction of a tile's run unless the user chose one: a tile's
 * viewpoint vote over weakly joined block groups sees only its part of the
 * scene. Measured on a generated 500K room in 4 tiles (seeds 1-3): the vote
 * over weak groups 5.30 / 5.27 / 4.20 % wrong, only disconnected parts (0)
 * 3.28 / 3.40 / 2.41 %; in one piece 3.24 / 2.38 / 2.64 % either way. */
#define DACPO_TILED_WEAK_EDGE_FRACTION 0.0

/* The parameters of a tile's run from the user's: normals estimated, and
 * weak_edge_fraction DACPO_TILED_WEAK_EDGE_FRACTION when it is the default. */
dacpo_params
dacpo_tiled_params(const dacpo_params* user);

/* "4G", "512M", "100K" or a plain number of bytes -> *bytes; 0 when it is not
 * a positive finite size. */
int
dacpo_tiled_parse_size(const char* text, double* bytes);

/* The evidence of tile pairs, summed as halo normals meet their owners': an
 * open-addressing map from (a, b) to its dacpo_tile_overlap (a tile borders a
 * few dozen others, so the pairs are O(tiles), never a T x T matrix). Zero-
 * initialise, then _init; entry[0 .. used) is the list for dacpo_tile_join(). */
typedef struct dacpo_tile_pairs {
  dacpo_tile_overlap* entry;
  size_t used, cap; /* entries */
  int32_t* slot;    /* 2 cap slots: entry index or -1 */
} dacpo_tile_pairs;

int
dacpo_tile_pairs_init(dacpo_tile_pairs* m, size_t tiles);

/* The entry of (a, b), created empty; NULL when memory ran out. */
dacpo_tile_overlap*
dacpo_tile_pairs_get(dacpo_tile_pairs* m, uint32_t a, uint32_t b);

void
dacpo_tile_pairs_free(dacpo_tile_pairs* m);

/* Budget in bytes -> max points per tile (at least 16). */
uint64_t
dacpo_tiled_points_for_memory(double bytes);

/* 0 on success; else 1 with a message in err (nothing written to output). */
int
dacpo_tiled_orient(const dacpo_tiled_options* opt,
                   dacpo_tiled_report* report,
                   char* err,
                   size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
