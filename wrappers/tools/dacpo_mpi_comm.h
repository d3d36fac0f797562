/* SPDX-License-Identifier: BSD-3-Clause */
/* Point-to-point messages and the all-ranks verdict of pcl_dacpo_orient_mpi
 * (its units and its distributed neighbour search), waiting without taking a
 * core from a rank that computes. */
#ifndef DACPO_MPI_COMM_H
#define DACPO_MPI_COMM_H

#include <mpi.h>
#include <stddef.h>

/* MB this rank sent and received. */
typedef struct dacpo_mpi_traffic {
  double sent_mb, received_mb;
} dacpo_mpi_traffic;

/* Completes a pending request, yielding and then sleeping between tests. */
void
dacpo_mpi_wait(MPI_Request* req);

/* Receives one message of any size from src (MPI_ANY_SOURCE allowed) with tag;
 * *from (may be NULL) gets the sender. The buffer is malloc'ed (one byte more
 * than *size); NULL if memory ran out. */
void*
dacpo_mpi_recv(int src, int tag, size_t* size, int* from, dacpo_mpi_traffic* traffic);

/* Sends size bytes (at most INT_MAX) to dst with tag and waits for completion. */
void
dacpo_mpi_send(
    const void* buf, size_t size, int dst, int tag, dacpo_mpi_traffic* traffic);

/* 1 if ok is non-zero on every rank: a failure anywhere ends the run everywhere. */
int
dacpo_mpi_all_ok(int ok);

/* owner[u] of `count` units of cost[u]: costliest first (ties by id) to the
 * least loaded rank (ties: the lowest rank); the same on every rank. malloc'ed
 * (NULL when memory ran out). */
int*
dacpo_mpi_deal(const double* cost, size_t count, int ranks);

#endif
