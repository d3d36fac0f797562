/* SPDX-License-Identifier: BSD-3-Clause */
/* See dacpo_mpi_comm.h. */
#define _POSIX_C_SOURCE 200809L /* nanosleep */

#include "dacpo_mpi_comm.h"

#include <sched.h>
#include <stdlib.h>
#include <time.h>

/* Between two tests of a pending transfer: the first tests only yield the
 * core (a large message moves in fragments, and each fragment needs both
 * ends to call MPI: sleeping 1 ms between them made a 200K-point run 40 %
 * slower); then sleep, so that a rank waiting for a peer that computes does
 * not take the core from it (more ranks than cores). */
static void
pause_between_tests(unsigned* tries)
{
  if (++*tries < 20000)
    sched_yield();
  else {
    const struct timespec ms = {0, 1000000};
    nanosleep(&ms, NULL);
  }
}

void
dacpo_mpi_wait(MPI_Request* req)
{
  int done = 0;
  unsigned tries = 0;
  MPI_Test(req, &done, MPI_STATUS_IGNORE);
  while (!done) {
    pause_between_tests(&tries);
    MPI_Test(req, &done, MPI_STATUS_IGNORE);
  }
}

/* Receives one message of any size from `src` (MPI_ANY_SOURCE allowed) with
 * `tag`; *from gets the sender. */
void*
dacpo_mpi_recv(int src, int tag, size_t* size, int* from, dacpo_mpi_traffic* traffic)
{
  int flag = 0;
  MPI_Status st;
  unsigned tries = 0;
  MPI_Iprobe(src, tag, MPI_COMM_WORLD, &flag, &st);
  while (!flag) {
    pause_between_tests(&tries);
    MPI_Iprobe(src, tag, MPI_COMM_WORLD, &flag, &st);
  }
  int count = 0;
  MPI_Get_count(&st, MPI_BYTE, &count);
  void* buf = malloc((size_t)count + 1);
  MPI_Request req;
  MPI_Irecv(buf, count, MPI_BYTE, st.MPI_SOURCE, tag, MPI_COMM_WORLD, &req);
  dacpo_mpi_wait(&req);
  *size = (size_t)count;
  if (from)
    *from = st.MPI_SOURCE;
  traffic->received_mb += (double)count / 1048576.0;
  return buf;
}

void
dacpo_mpi_send(
    const void* buf, size_t size, int dst, int tag, dacpo_mpi_traffic* traffic)
{
  MPI_Request req;
  MPI_Isend(buf, (int)size, MPI_BYTE, dst, tag, MPI_COMM_WORLD, &req);
  dacpo_mpi_wait(&req);
  traffic->sent_mb += (double)size / 1048576.0;
}

/* A failure on any rank ends the run on every rank. The other ranks also wait
 * here through rank 0's stages 0-1: a blocking MPI_Allreduce would spin on a
 * core that rank 0's threads may need when ranks share cores (no gain could be
 * measured on 2 cores: rank 0's stages 0-1 of the 10M floor took 44-66 s over
 * runs with 1-4 ranks either way, run-to-run noise included). */
int
dacpo_mpi_all_ok(int ok)
{
  int all = 0;
  MPI_Request req;
  MPI_Iallreduce(&ok, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD, &req);
  dacpo_mpi_wait(&req);
  return all;
}

/* owner[u] for `count` units of cost[u]: costliest first (ties by id) to the
 * least loaded rank (ties: the lowest rank). The same on every rank. */
int*
dacpo_mpi_deal(const double* cost, size_t count, int ranks)
{
  int* owner = malloc((count + 1) * sizeof(int));
  size_t* order = malloc((count + 1) * sizeof(size_t));
  double* load = calloc((size_t)ranks, sizeof(double));
  if (!owner || !order || !load) {
    free(owner);
    owner = NULL;
    goto done;
  }
  for (size_t u = 0; u < count; ++u)
    order[u] = u;
  for (size_t i = 1; i < count; ++i) { /* insertion sort: a few thousand units */
    const size_t u = order[i];
    size_t j = i;
    while (j > 0 && (cost[order[j - 1]] < cost[u] ||
                     (cost[order[j - 1]] == cost[u] && order[j - 1] > u))) {
      order[j] = order[j - 1];
      --j;
    }
    order[j] = u;
  }
  for (size_t i = 0; i < count; ++i) {
    int best = 0;
    for (int r = 1; r < ranks; ++r)
      if (load[r] < load[best])
        best = r;
    owner[order[i]] = best;
    load[best] += cost[order[i]];
  }
done:
  free(order);
  free(load);
  return owner;
}
