/* SPDX-License-Identifier: BSD-3-Clause */
/* pcl_dacpo_orient_mpi -tiles: the tiles of dacpo_tiled.h over MPI ranks, no
 * rank holding the whole cloud. */
#ifndef DACPO_MPI_TILES_H
#define DACPO_MPI_TILES_H

#include "dacpo_mpi_comm.h"

#include <dacpo/dacpo_advanced.h>

#include <stdint.h>

typedef struct dacpo_mpi_tiles_report {
  double wall[5];        /* read + sample + plan, route, tiles, join, write */
  double busy;           /* seconds in this rank's dacpo_orient() runs */
  double tiles;          /* tiles run here */
  double held_points;    /* own + halo points of this rank's tiles */
  double largest_tile;   /* own + halo points of its largest tile */
  double flipped_tiles;  /* (rank 0) tiles the join turned over */
  double num_tiles;      /* (rank 0) tiles in the plan */
  double halo;           /* halo width used */
  dacpo_mpi_traffic traffic;
} dacpo_mpi_tiles_report;

/* Every rank reads its own byte range of the binary PLY `in`, points go to the
 * ranks of their tiles (dealt by estimated size), each rank orients its tiles
 * with dacpo_orient() (params->estimate_normals is forced on), the join runs on
 * rank 0, and every rank writes the normals of its own input range into `out`
 * (binary PLY, x y z nx ny nz, MPI-IO). The output is the same bytes as
 * pcl_dacpo_orient -memory with the same tile size for any number of ranks.
 * Returns 1 on every rank when all succeeded; else 0 (message printed by the
 * rank that failed). */
int
dacpo_mpi_tiles_orient(const char* in,
                       const char* out,
                       const dacpo_params* params,
                       uint64_t max_points,
                       double halo,
                       int rank,
                       int ranks,
                       dacpo_mpi_tiles_report* rep);

#endif
